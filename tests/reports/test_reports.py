"""Reports: the order roll-up, the vehicle sampler, the page and its CSV exports."""

import csv
import io
from datetime import UTC, datetime, timedelta

import pytest
from django.db.models import Sum
from django.test import Client

from maps.models import Map, Station
from orders.models import TransportOrder
from reports.models import LEAD_TIME_BUCKETS, ErrorCount, LeadTimeCount, VehicleHour
from reports.services import SETTLE, bucket_of, roll_up_orders, sample_vehicles
from robots.models import Vehicle
from tests.factories import user_with_role

pytestmark = pytest.mark.django_db
T0 = datetime(2026, 11, 20, 8, 0, tzinfo=UTC)
Status = TransportOrder.Status


def ended(
    demo_map: Map,
    vehicle: Vehicle | None,
    status: str,
    *,
    finished: datetime,
    lead: timedelta = timedelta(minutes=4),
    deadline: datetime | None = None,
) -> TransportOrder:
    pick, drop = Station.objects.filter(map=demo_map).order_by("station_id")[:2]
    order = TransportOrder.objects.create(
        source=pick, destination=drop, vehicle=vehicle, status=status, deadline=deadline
    )
    created = finished - lead
    TransportOrder.objects.filter(pk=order.pk).update(
        created_at=created,
        assigned_at=created + lead / 4 if vehicle else None,
        started_at=created + lead / 2 if vehicle else None,
        finished_at=finished,
    )
    return order


def hour_totals(**filters: object) -> dict[str, int]:
    return VehicleHour.objects.filter(**filters).aggregate(
        finished=Sum("finished"), failed=Sum("failed"), cancelled=Sum("cancelled"),
        on_time=Sum("on_time"), with_deadline=Sum("with_deadline"),
    )  # fmt: skip


def test_the_roll_up_counts_every_ended_order_exactly_once(demo_map: Map) -> None:
    agv = Vehicle.objects.create(manufacturer="Acme", serial_number="AGV-1")
    ended(
        demo_map,
        agv,
        Status.FINISHED,
        finished=T0 + timedelta(minutes=5),
        deadline=T0 + timedelta(hours=1),
    )
    ended(demo_map, agv, Status.FINISHED, finished=T0 + timedelta(minutes=50), deadline=T0)  # late
    ended(demo_map, agv, Status.FAILED, finished=T0 + timedelta(hours=1, minutes=1))
    ended(demo_map, None, Status.CANCELLED, finished=T0 + timedelta(minutes=7))
    TransportOrder.objects.create(  # still open: not counted
        source=Station.objects.filter(map=demo_map).first(),
        destination=Station.objects.filter(map=demo_map).last(),
    )

    assert roll_up_orders(now=T0 + timedelta(hours=2)) == 4
    assert roll_up_orders(now=T0 + timedelta(hours=2, minutes=1)) == 0  # nothing twice
    assert hour_totals(hour=T0, vehicle=agv) == {
        "finished": 2, "failed": 0, "cancelled": 0, "on_time": 1, "with_deadline": 2,
    }  # fmt: skip
    assert hour_totals(hour=T0 + timedelta(hours=1), vehicle=agv)["failed"] == 1
    assert hour_totals(vehicle__isnull=True)["cancelled"] == 1

    # An order ending later is added on the next run, to the figures already there.
    ended(demo_map, agv, Status.FINISHED, finished=T0 + timedelta(hours=2, minutes=30))
    assert roll_up_orders(now=T0 + timedelta(hours=2, minutes=30)) == 0  # not settled yet
    assert roll_up_orders(now=T0 + timedelta(hours=2, minutes=30) + SETTLE * 2) == 1
    assert hour_totals(vehicle=agv)["finished"] == 3


def test_lead_times_land_in_their_buckets_per_stage(demo_map: Map) -> None:
    agv = Vehicle.objects.create(manufacturer="Acme", serial_number="AGV-1")
    ended(demo_map, agv, Status.FINISHED, finished=T0, lead=timedelta(minutes=4))
    ended(demo_map, agv, Status.FINISHED, finished=T0, lead=timedelta(hours=3))
    roll_up_orders(now=T0 + timedelta(minutes=1))
    counts = {
        (row.stage, row.bucket): (row.count, row.seconds)
        for row in LeadTimeCount.objects.filter(vehicle=agv)
    }
    assert counts[("total", bucket_of(240))] == (1, 240)  # 4 minutes: the ≤ 300 s band
    assert counts[("total", len(LEAD_TIME_BUCKETS))] == (1, 3 * 3600)  # beyond the last bound
    assert counts[("waiting", bucket_of(60))][0] == 1  # a quarter of 4 minutes


def test_the_sampler_turns_looks_into_time_by_state_distance_and_energy(demo_map: Map) -> None:
    online = {
        "connection": "ONLINE",
        "operating_mode": "AUTOMATIC",
        "map_id": "m",
        "x": 0.0,
        "y": 0.0,
    }
    idle = Vehicle.objects.create(
        manufacturer="A", serial_number="idle", battery_charge=80, **online
    )
    charging = Vehicle.objects.create(
        manufacturer="A", serial_number="chg", charging=True, **online
    )
    broken = Vehicle.objects.create(
        manufacturer="A",
        serial_number="err",
        errors=[{"errorType": "bumper", "errorLevel": "FATAL"}],
        **online,
    )
    offline = Vehicle.objects.create(manufacturer="A", serial_number="off", connection="OFFLINE")
    busy = Vehicle.objects.create(manufacturer="A", serial_number="busy", **online)
    ended(demo_map, busy, Status.IN_PROGRESS, finished=T0)  # an active order makes it busy

    assert sample_vehicles(now=T0) == 5  # the first look only sets the marks
    assert not VehicleHour.objects.exclude(
        busy_s=0, idle_s=0, charging_s=0, error_s=0, offline_s=0
    ).exists()
    Vehicle.objects.filter(pk=idle.pk).update(x=3.0, y=4.0, battery_charge=78.5)
    sample_vehicles(now=T0 + timedelta(seconds=15))
    sample_vehicles(now=T0 + timedelta(minutes=30))  # the sampler was down: counts 60 s at most

    row = VehicleHour.objects.get(vehicle=idle, hour=T0)
    assert (row.idle_s, row.busy_s, row.distance_m, row.energy_pct) == (75, 0, 5.0, 1.5)
    assert VehicleHour.objects.get(vehicle=charging).charging_s == 75
    assert VehicleHour.objects.get(vehicle=broken).error_s == 75
    assert VehicleHour.objects.get(vehicle=offline).offline_s == 75
    assert VehicleHour.objects.get(vehicle=busy).busy_s == 75
    errors = ErrorCount.objects.get(vehicle=broken)
    assert (errors.error_type, errors.count) == ("bumper", 1)  # once, not once per look


@pytest.fixture
def manager_client() -> Client:
    client = Client()
    client.force_login(user_with_role("manager"))
    return client


def test_the_page_shows_the_figures_and_each_table_exports_as_csv(
    demo_map: Map, manager_client: Client
) -> None:
    agv = Vehicle.objects.create(manufacturer="Acme", serial_number="AGV-1")
    ended(
        demo_map,
        agv,
        Status.FINISHED,
        finished=T0 + timedelta(minutes=5),
        deadline=T0 + timedelta(hours=1),
    )
    roll_up_orders(now=T0 + timedelta(hours=1))
    query = "start=2026-11-20&end=2026-11-20"
    page = manager_client.get(f"/reports/?{query}")
    assert page.status_code == 200
    html = page.content.decode()
    assert '<svg class="chart"' in html
    assert "<strong>1</strong> orders finished" in html
    assert "<strong>100 %</strong> of 1 orders with a deadline" in html

    response = manager_client.get(f"/reports/throughput.csv?{query}")
    assert response["Content-Type"].startswith("text/csv")
    rows = list(csv.reader(io.StringIO(response.content.decode())))
    assert rows[0] == ["hour", "finished", "failed", "cancelled"]
    assert len(rows) == 1 + 24
    assert sum(int(r[1]) for r in rows[1:]) == 1
    for name in ("shifts", "lead_times", "utilisation", "errors"):
        assert manager_client.get(f"/reports/{name}.csv?{query}").status_code == 200
    assert manager_client.get(f"/reports/nothing.csv?{query}").status_code == 404


def test_bad_filters_get_a_reason_and_anonymous_users_the_login(manager_client: Client) -> None:
    response = manager_client.get("/reports/?start=2026-11-20&end=2026-11-01")
    assert response.status_code == 400
    assert "start date is after the end date" in response.content.decode()
    assert manager_client.get("/reports/?start=2026-01-01&end=2026-12-31").status_code == 400
    assert manager_client.get("/reports/throughput.csv?start=nonsense").status_code == 400
    assert Client().get("/reports/").status_code == 302
