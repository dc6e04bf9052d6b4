"""The staff orders pages with Django's test client: login, list, create, change, recurring."""

import pytest
from django.conf import settings
from django.shortcuts import resolve_url
from django.test import Client

from maps.models import Station
from orders import services
from orders.models import OrderEvent, RecurringOrder, TransportOrder
from tests.factories import VehicleFactory, user_with_role


@pytest.fixture
def staff(db: None) -> Client:
    user = user_with_role("operator", "lena", password="pw-lena-1")
    client = Client()
    client.force_login(user)
    return client


def pick_drop(demo_map, pick: str = "PICK-1", drop: str = "DROP-1") -> TransportOrder:
    return services.create_transport_order(
        source=Station.objects.get(station_id=pick),
        destination=Station.objects.get(station_id=drop),
    )


def test_pages_need_a_login(client, demo_map) -> None:
    for url in ("/orders/", "/orders/new/", "/orders/recurring/"):
        response = client.get(url)
        assert response.status_code == 302
        assert response["Location"] == f"{resolve_url(settings.LOGIN_URL)}?next={url}"


def test_the_list_shows_steps_status_and_why_an_order_waits(staff, demo_map) -> None:
    waiting = pick_drop(demo_map)
    services.dispatch_pending_orders()
    done = pick_drop(demo_map, "PICK-2", "DROP-2")
    TransportOrder.objects.filter(pk=done.pk).update(status="FINISHED")

    page = staff.get("/orders/").content.decode()
    everything = staff.get("/orders/?status=ALL").content.decode()
    by_station = staff.get("/orders/?status=ALL&station=PICK-2").content.decode()

    assert f'id="order-{waiting.pk}"' in page
    assert "no vehicle online" in page
    assert f'id="order-{done.pk}"' not in page  # open orders by default
    assert f'id="order-{done.pk}"' in everything
    assert f'id="order-{waiting.pk}"' not in by_station


def test_staff_create_a_multi_stop_order_and_see_a_refusal_explained(staff, demo_map) -> None:
    ids = {s.station_id: s.pk for s in Station.objects.all()}
    form = {
        "step-TOTAL_FORMS": "6",
        "step-INITIAL_FORMS": "0",
        "step-0-station": ids["PICK-1"],
        "step-0-operation": "PICK",
        "step-1-station": ids["PICK-2"],
        "step-1-operation": "ACTION",
        "step-1-action_type": "detectObject",
        "step-2-station": ids["DROP-3"],
        "step-2-operation": "DROP",
        "priority": "4",
        "load_type": "EPAL",
    }
    for row in range(3, 6):
        form[f"step-{row}-operation"] = "PICK"

    created = staff.post("/orders/new/", form)
    refused = staff.post("/orders/new/", {**form, "step-1-action_type": ""})

    assert created.status_code == 302
    order = TransportOrder.objects.get()
    assert [s.vda_action_type for s in order.steps.all()] == ["pick", "detectObject", "drop"]
    assert order.priority == 4
    assert refused.status_code == 200
    assert "a custom action needs an action_type" in refused.content.decode()
    assert TransportOrder.objects.count() == 1


def test_staff_cancel_reprioritise_and_reassign(staff, demo_map) -> None:
    vehicle = VehicleFactory()
    order = pick_drop(demo_map)

    staff.post(f"/orders/{order.pk}/priority/", {"priority": "7"})
    staff.post(f"/orders/{order.pk}/reassign/", {"vehicle": vehicle.pk})
    bad = staff.post(f"/orders/{order.pk}/priority/", {"priority": "lots"}, follow=True)
    staff.post(f"/orders/{order.pk}/cancel/")
    again = staff.post(f"/orders/{order.pk}/cancel/", follow=True)

    order.refresh_from_db()
    assert (order.priority, order.intended_vehicle, order.status) == (7, vehicle, "CANCELLED")
    assert "priority must be a whole number" in bad.content.decode()
    assert "cannot be cancelled" in again.content.decode()
    kinds = list(order.events.values_list("kind", flat=True))
    assert kinds == [
        OrderEvent.Kind.CREATED,
        OrderEvent.Kind.UPDATED,
        OrderEvent.Kind.UPDATED,
        OrderEvent.Kind.CANCELLED,
    ]


def test_changes_need_the_permission(db, demo_map) -> None:
    order = pick_drop(demo_map)
    client = Client()
    client.force_login(user_with_role("manager", "viewer"))  # reads operations, changes none

    assert client.get("/orders/").status_code == 200
    assert client.post(f"/orders/{order.pk}/cancel/").status_code == 403
    assert client.get("/orders/new/").status_code == 403
    order.refresh_from_db()
    assert order.status == "NEW"


def test_reassigning_gives_an_unsent_assignment_back_to_dispatch(staff, demo_map) -> None:
    first = VehicleFactory(last_node_id="A1.3")
    other = VehicleFactory(last_node_id="A5.0")
    order = pick_drop(demo_map)
    services.dispatch_pending_orders()
    order.refresh_from_db()
    assert order.vehicle == first

    staff.post(f"/orders/{order.pk}/reassign/", {"vehicle": other.pk})
    TransportOrder.objects.filter(pk=order.pk).update(sent_at=None)
    services.dispatch_pending_orders()

    order.refresh_from_db()
    assert (order.vehicle, order.intended_vehicle) == (other, other)
    assert order.events.filter(kind=OrderEvent.Kind.REQUEUED).exists()
    TransportOrder.objects.filter(pk=order.pk).update(sent_at=order.assigned_at)
    refused = staff.post(f"/orders/{order.pk}/reassign/", {"vehicle": first.pk}, follow=True)
    assert "sent to its vehicle" in refused.content.decode()


def test_staff_set_up_a_recurring_order(staff, demo_map) -> None:
    ids = {s.station_id: s.pk for s in Station.objects.all()}
    form = {
        "name": "A to B",
        "source": ids["PICK-1"],
        "destination": ids["DROP-2"],
        "interval_minutes": "15",
        "weekdays": ["0", "1", "2", "3", "4"],
        "window_start": "06:00",
        "window_end": "22:00",
        "priority": "0",
    }

    saved = staff.post("/orders/recurring/", form)
    refused = staff.post("/orders/recurring/", {**form, "window_end": "05:00"})

    assert saved.status_code == 302
    schedule = RecurringOrder.objects.get()
    assert (schedule.weekdays, schedule.steps[1]["station"]) == ([0, 1, 2, 3, 4], "DROP-2")
    assert "window must end after it starts" in refused.content.decode()
    assert "A to B" in staff.get("/orders/recurring/").content.decode()
