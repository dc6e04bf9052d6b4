"""End to end with traffic management (on by default): control, a Celery worker and 4 simulated
vehicles as processes. Four orders cross the warehouse (pick in column c, drop in column 5 - c),
a share of the vehicles' moves is delayed, and the simulator's own collision checker must report
no footprint overlap while every order finishes."""

import json
import time
from pathlib import Path

import pytest

from maps.demo import warehouse_layout
from maps.models import Station
from maps.services import create_layout
from orders.models import TransportOrder
from orders.services import create_transport_order
from robots.models import Vehicle
from tests.e2e.conftest import start_fleet
from tests.e2e.processes import wait_until

pytestmark = [pytest.mark.e2e, pytest.mark.django_db(transaction=True)]


def test_crossing_orders_with_delays_finish_without_collision(
    fleet_env: dict[str, str], tmp_path: Path
) -> None:
    layout = create_layout(spec=warehouse_layout(columns=6, rows=4))
    summary = tmp_path / "simulator-summary.json"
    delays = ("--delay-share", "0.15", "--delay-range", "5,30", "--delay-seed", "3")
    processes = start_fleet(
        fleet_env, tmp_path, layout, vehicles=4, extra=(*delays, "--summary", str(summary))
    )
    started = time.monotonic()
    try:
        wait_until(
            lambda: Vehicle.objects.filter(connection="ONLINE").count() == 4,
            60,
            "4 vehicles registered online",
            processes,
        )
        picks = {s.name: s for s in Station.objects.filter(map=layout, kind=Station.Kind.PICK)}
        drops = {s.name: s for s in Station.objects.filter(map=layout, kind=Station.Kind.DROP)}
        orders = [
            create_transport_order(
                source=picks[f"PICK-{c}"], destination=drops[f"DROP-{5 - c}"], load_id=f"L{c}"
            )
            for c in range(1, 5)
        ]
        wait_until(
            lambda: (
                not TransportOrder.objects.filter(status__in=TransportOrder.OPEN_STATUSES).exists()
            ),
            300,
            "all orders closed",
            processes,
        )
        duration = time.monotonic() - started
    finally:
        codes = {p.name: p.terminate() for p in processes}

    statuses = {
        o.pk: o.status for o in TransportOrder.objects.filter(pk__in=[o.pk for o in orders])
    }
    assert set(statuses.values()) == {"FINISHED"}, statuses
    assert codes == {"control": 0, "worker": 0, "simulator": 0}, codes
    report = json.loads(summary.read_text())
    assert report["vehicles"] == 4
    assert report["steps"] > 100  # the checker ran through the whole drive
    assert report["delays_injected"] > 0, report
    assert report["collisions"] == 0, report["events"]
    finished_at = {
        o.destination.node.node_id for o in TransportOrder.objects.filter(pk__in=statuses)
    }
    assert set(Vehicle.objects.values_list("last_node_id", flat=True)) >= finished_at
    print(
        f"e2e traffic: 4 crossing orders, {report['delays_injected']} delays, "
        f"{report['collisions']} collisions in {duration:.1f} s"
    )
