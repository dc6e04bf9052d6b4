"""The operations pages: fleet overview, vehicles list, orders board, alerts filters, navigation."""

import re
from datetime import timedelta

import pytest
from django.test import Client
from django.utils import timezone

from alerts.models import Alert
from battery.models import Charger, ChargeSession
from maintenance.models import VehicleCounters
from maps.models import Station
from orders import services
from orders.models import OrderEvent, TransportOrder
from tests.factories import VehicleFactory, user_with_role

pytestmark = pytest.mark.django_db


def signed_in(role: str) -> Client:
    client = Client()
    client.force_login(user_with_role(role))
    return client


def tile_counts(html: str, attribute: str) -> dict[str, int]:
    pattern = rf'data-{attribute}="([^"]+)"><strong class="tile-count">(\d+)</strong>'
    return {key: int(count) for key, count in re.findall(pattern, html)}


def order(demo_map, status: str = "NEW", **fields) -> TransportOrder:
    created = services.create_transport_order(
        source=Station.objects.get(station_id="PICK-1"),
        destination=Station.objects.get(station_id="DROP-1"),
    )
    TransportOrder.objects.filter(pk=created.pk).update(status=status, **fields)
    created.refresh_from_db()
    return created


def test_the_overview_counts_match_the_database(demo_map) -> None:
    VehicleFactory.create_batch(2)  # idle
    VehicleFactory(driving=True)
    VehicleFactory(charging=True)
    VehicleFactory(connection="OFFLINE")
    VehicleFactory(errors=[{"errorType": "bumper", "errorLevel": "FATAL"}])
    VehicleFactory(operating_mode="MANUAL")
    held = VehicleFactory()
    VehicleCounters.objects.create(vehicle=held, out_of_service=True, out_of_service_reason="tyre")
    busy = VehicleFactory()
    order(demo_map, "IN_PROGRESS", vehicle=busy)
    order(demo_map)
    order(demo_map)
    order(demo_map, "FAILED", finished_at=timezone.now())
    order(demo_map, "FINISHED", finished_at=timezone.now() - timedelta(days=2))  # not today
    Alert.objects.create(cause="a", severity="FATAL", message="x")
    Alert.objects.create(cause="b", severity="WARNING", message="y")
    Alert.objects.create(cause="c", severity="WARNING", message="z", status="RESOLVED")
    charger = Charger.objects.create(station=Station.objects.filter(kind="CHARGE").first())
    ChargeSession.objects.create(
        vehicle=VehicleFactory(charging=True), charger=charger, status="CHARGING"
    )

    html = signed_in("manager").get("/overview/").content.decode()

    assert tile_counts(html, "state") == {
        "driving": 2,
        "idle": 2,
        "charging": 2,
        "error": 1,
        "offline": 1,
        "manual": 1,
        "out_of_service": 1,
    }
    orders = tile_counts(html, "status")
    assert (orders["NEW"], orders["IN_PROGRESS"], orders["FAILED"], orders["FINISHED"]) == (
        2,
        1,
        1,
        0,
    )
    alerts = tile_counts(html, "severity")
    assert (alerts["FATAL"], alerts["WARNING"], alerts["INFO"]) == (1, 1, 0)
    assert 'href="/alerts/?severity=FATAL"' in html
    assert "tyre" in html  # why a vehicle is out of service
    assert re.search(r'data-chargers="in-use"><strong class="tile-count">1 / 1<', html)


def test_the_vehicles_list_filters_sorts_and_links_to_each_vehicle(demo_map) -> None:
    VehicleFactory(serial_number="AGV-LOW", battery_charge=12.0)
    VehicleFactory(serial_number="AGV-OFF", connection="OFFLINE", battery_charge=50.0)
    VehicleFactory(serial_number="AGV-BUSY", driving=True, battery_charge=80.0)
    client = signed_in("operator")

    def shown(query: str) -> list[str]:
        html = client.get(f"/vehicles/?{query}").content.decode()
        return re.findall(r'<tr data-vehicle="([^"]+)"', html)

    assert shown("") == ["AGV-BUSY", "AGV-LOW", "AGV-OFF"]
    assert shown("state=offline") == ["AGV-OFF"]
    assert shown("state=driving") == ["AGV-BUSY"]
    assert shown("connection=ONLINE") == ["AGV-BUSY", "AGV-LOW"]
    assert shown("battery_below=60") == ["AGV-LOW", "AGV-OFF"]
    assert shown("q=low") == ["AGV-LOW"]
    assert shown("sort=battery&desc=on") == ["AGV-BUSY", "AGV-OFF", "AGV-LOW"]
    assert 'href="/vehicles/sim/AGV-LOW/"' in client.get("/vehicles/").content.decode()
    assert client.get("/vehicles/?battery_below=lots").status_code == 200  # ignored, shown


def test_operations_pages_need_the_operations_permission(demo_map) -> None:
    client = Client()
    client.force_login(user_with_role("operator", username="x"))
    plain = Client()
    from django.contrib.auth import get_user_model

    plain.force_login(get_user_model().objects.create_user("nobody"))

    for url in ("/overview/", "/vehicles/", "/orders/"):
        assert client.get(url).status_code == 200
        assert plain.get(url).status_code == 403
        assert Client().get(url).status_code == 302  # to the login page


def test_the_board_shows_queued_running_failed_with_reasons_and_finished_today(demo_map) -> None:
    vehicle = VehicleFactory()
    queued = order(demo_map, priority=5, dispatch_note="no vehicle online")
    running = order(demo_map, "IN_PROGRESS", vehicle=vehicle)
    failed = order(demo_map, "FAILED", finished_at=timezone.now(), failure_reason="rejected")
    OrderEvent.objects.create(order=failed, kind="REQUEUED", detail={"reason": "vehicle lost"})
    OrderEvent.objects.create(order=failed, kind="FAILED", detail={"reason": "rejected"})
    finished = order(demo_map, "FINISHED", finished_at=timezone.now())
    old = order(demo_map, "FINISHED", finished_at=timezone.now() - timedelta(days=2))

    html = signed_in("operator").get("/orders/").content.decode()

    def column(key: str) -> str:
        start = html.index(f'id="column-{key}"')
        return html[start : html.index("</section>", start)]

    assert f'id="order-{queued.pk}"' in column("queued")
    assert "no vehicle online" in column("queued")
    assert f'id="order-{running.pk}"' in column("running")
    assert f'id="order-{failed.pk}"' in column("failed")
    assert "requeued: vehicle lost" in column("failed")
    assert f'id="order-{finished.pk}"' in column("finished")
    assert f'id="order-{old.pk}"' not in html
    assert f'action="/orders/{queued.pk}/cancel/"' in column("queued")  # operators may cancel


def test_the_board_hides_actions_from_a_manager_and_the_list_stays_reachable(demo_map) -> None:
    queued = order(demo_map)
    client = signed_in("manager")

    board = client.get("/orders/").content.decode()
    listed = client.get("/orders/?view=list").content.decode()

    assert f'id="order-{queued.pk}"' in board
    assert f'action="/orders/{queued.pk}/cancel/"' not in board
    assert 'id="orders-table"' in listed


def test_the_alerts_list_filters_by_state_and_vehicle(demo_map) -> None:
    first, second = VehicleFactory(serial_number="AGV-A"), VehicleFactory(serial_number="AGV-B")
    Alert.objects.create(cause="a", vehicle=first, message="on A")
    Alert.objects.create(cause="b", vehicle=second, message="on B", status="ACKNOWLEDGED")
    client = signed_in("operator")

    by_vehicle = client.get("/alerts/?vehicle=agv-a").content.decode()
    acknowledged = client.get("/alerts/?show=ACKNOWLEDGED").content.decode()

    assert "on A" in by_vehicle
    assert "on B" not in by_vehicle
    assert "on B" in acknowledged
    assert "on A" not in acknowledged


@pytest.mark.parametrize(
    ("role", "present", "absent"),
    [
        ("operator", ["Overview", "Vehicles", "Orders", "Alerts"], ["Reports", "Layouts", "Audit"]),
        ("manager", ["Overview", "Reports", "Audit"], ["Layouts"]),
        ("administrator", ["Overview", "Reports", "Layouts", "Audit", "Inventory"], []),
    ],
)
def test_the_navigation_shows_the_pages_a_role_may_open(demo_map, role, present, absent) -> None:
    html = signed_in(role).get("/overview/").content.decode()
    nav = html[html.index('<nav class="topnav"') : html.index("</nav>")]
    links = re.findall(r">([A-Za-z ]+)</a>", nav)

    assert set(present) <= set(links)
    assert not set(absent) & set(links)
