"""The traffic-wait report: recorded waits, the Celery roll-up, figures, heatmap and CSV."""

import csv
import io
from datetime import timedelta

import pytest
from django.test import Client
from django.utils import timezone

from reports import wait_selectors, waits
from reports.history import generate_history
from reports.models import TrafficWait, WaitDayCount, WaitHourCount, WaitNodeDay
from reports.selectors import ReportFilter
from tests.factories import VehicleFactory, user_with_role

pytestmark = pytest.mark.django_db


def episode(vehicle, node: str, seconds: float, minutes_ago: int = 30) -> dict:
    return {
        "vehicle_id": vehicle.pk,
        "map_id": "demo",
        "node_id": node,
        "x": 0.0,
        "y": 0.0,
        "started_at": timezone.now() - timedelta(minutes=minutes_ago),
        "seconds": seconds,
        "waited_for": ["AGV-X"],
    }


@pytest.fixture
def recorded(demo_map):
    first, second = VehicleFactory(serial_number="AGV-1"), VehicleFactory(serial_number="AGV-2")
    waits.record_traffic_waits(
        episodes=[episode(first, "A1.1", s) for s in (3.0, 4.0, 5.0, 8.0)]
        + [episode(second, "A1.1", 40.0), episode(second, "A2.1", 1.0)]
    )
    return first, second


def today() -> ReportFilter:
    day = timezone.localdate()
    return ReportFilter(day - timedelta(days=1), day)


def test_the_roll_up_counts_each_wait_once(recorded) -> None:
    assert waits.roll_up_traffic_waits() == 6
    assert waits.roll_up_traffic_waits() == 0  # nothing new

    assert sum(WaitHourCount.objects.values_list("count", flat=True)) == 6
    assert sum(WaitDayCount.objects.values_list("count", flat=True)) == 6
    node = WaitNodeDay.objects.get(node_id="A1.1", vehicle=recorded[1])
    assert (node.count, node.seconds) == (1, 40.0)
    fleet = WaitNodeDay.objects.get(node_id="A1.1", vehicle=None)  # what the unfiltered map reads
    assert (fleet.count, fleet.seconds) == (5, 60.0)
    assert TrafficWait.objects.get(seconds=40.0).waited_for == ["AGV-X"]


def test_mean_and_p95_per_vehicle_and_hour_and_the_heatmap(recorded) -> None:
    waits.roll_up_traffic_waits()

    per_vehicle = {s.label: s for s in wait_selectors.waits_by_vehicle(today())}
    hours = wait_selectors.waits_by_hour(today())
    heatmap = wait_selectors.wait_heatmap(today())

    first = per_vehicle["sim/AGV-1"]
    assert (first.count, first.mean_s, first.p95) == (4, 5.0, "≤ 10 s")
    assert per_vehicle["sim/AGV-2"].p95 == "≤ 60 s"
    assert sum(stats.count for _, stats in hours) == 6
    assert heatmap is not None
    assert heatmap.map_id == "demo"
    assert {h.node_id: h.seconds for h in heatmap.heat} == {"A1.1": 60.0, "A2.1": 1.0}
    assert len(heatmap.edges) > 10  # the layout drawn under the heat


def test_only_the_chosen_vehicles_count_per_vehicle_and_on_the_heatmap(recorded) -> None:
    waits.roll_up_traffic_waits()
    chosen = ReportFilter(today().start, today().end, (recorded[0].pk,))

    assert [s.label for s in wait_selectors.waits_by_vehicle(chosen)] == ["sim/AGV-1"]
    heatmap = wait_selectors.wait_heatmap(chosen)
    assert heatmap is not None
    assert {h.node_id: h.seconds for h in heatmap.heat} == {"A1.1": 20.0}


def test_the_page_draws_the_heatmap_and_the_csv_lists_every_node(recorded) -> None:
    waits.roll_up_traffic_waits()
    client = Client()
    client.force_login(user_with_role("manager"))

    page = client.get("/reports/").content.decode()
    nodes = client.get("/reports/waits_nodes.csv").content.decode()
    vehicles = client.get("/reports/waits_vehicles.csv").content.decode()

    assert 'id="traffic-waits"' in page
    assert page.count('class="heat"') == 2
    assert 'data-node="A1.1" data-seconds="60"' in page
    rows = list(csv.reader(io.StringIO(nodes)))
    assert rows[0] == ["map", "node", "x", "y", "waits", "wait_s"]
    assert [r[1] for r in rows[1:]] == ["A1.1", "A2.1"]
    assert "sim/AGV-1,4,20.0,5.0,≤ 10 s" in vehicles


def test_generated_history_has_waits_on_the_layout(db) -> None:
    generate_history(vehicles=3, days=2, orders_per_hour=1)

    heatmap = wait_selectors.wait_heatmap(today())
    assert heatmap is not None
    assert heatmap.heat
    assert len(wait_selectors.waits_by_vehicle(today())) == 3
    per_vehicle = WaitNodeDay.objects.filter(vehicle__isnull=False)
    assert per_vehicle.values("vehicle", "node_id").distinct().count() <= 3 * 8
