"""End to end on the real services: control, a Celery worker and 3 simulated vehicles as processes
against Mosquitto, PostgreSQL and Redis; 5 transport orders must all finish."""

import time
from pathlib import Path

import pytest

from maps.demo import warehouse_layout
from maps.models import Station
from maps.services import create_layout
from orders.models import OrderEvent, TransportOrder
from orders.services import create_transport_order
from robots.models import Vehicle
from tests.e2e.conftest import start_fleet
from tests.e2e.processes import wait_until

pytestmark = [pytest.mark.e2e, pytest.mark.django_db(transaction=True)]


@pytest.mark.parametrize("version", ["2.0.0", "2.1.0", "3.0.0"])
def test_five_orders_finish_with_three_vehicles(
    fleet_env: dict[str, str], tmp_path: Path, version: str
) -> None:
    layout = create_layout(spec=warehouse_layout(columns=6, rows=4))
    processes = start_fleet(fleet_env, tmp_path, layout, vehicles=3, version=version)
    started = time.monotonic()
    try:
        wait_until(
            lambda: Vehicle.objects.filter(connection="ONLINE").count() == 3,
            60,
            "3 vehicles registered online",
            processes,
        )
        picks = list(Station.objects.filter(map=layout, kind=Station.Kind.PICK))
        drops = list(Station.objects.filter(map=layout, kind=Station.Kind.DROP))
        orders = [
            create_transport_order(
                source=picks[i % len(picks)],
                destination=drops[-1 - i % len(drops)],
                load_id=f"LOAD-{i}",
            )
            for i in range(5)
        ]

        wait_until(
            lambda: (
                not TransportOrder.objects.filter(status__in=TransportOrder.OPEN_STATUSES).exists()
            ),
            240,
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
    for order in TransportOrder.objects.filter(pk__in=statuses).select_related("destination__node"):
        kinds = list(order.events.values_list("kind", flat=True))
        assert kinds == [
            "CREATED",
            "ASSIGNED",
            "STARTED",
            "STEP_REACHED",
            "STEP_REACHED",
            "FINISHED",
        ], (order.pk, kinds)
        steps = [e.detail["step"] for e in order.events.filter(kind=OrderEvent.Kind.STEP_REACHED)]
        assert steps == ["pick", "drop"]
    for vehicle in Vehicle.objects.all():
        last = vehicle.transport_orders.filter(status="FINISHED").order_by("-finished_at").first()
        if last is not None:
            assert vehicle.last_node_id == last.destination.node.node_id, vehicle
        assert vehicle.errors == [], vehicle.errors
    assert set(Vehicle.objects.values_list("protocol_version", flat=True)) == {version}
    print(f"e2e {version}: 5 orders finished by 3 vehicles in {duration:.1f} s")
