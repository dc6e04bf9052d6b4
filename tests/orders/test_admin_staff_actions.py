"""Admin: staff cancel, reprioritise and reassign orders through the services; recurring
orders and sequences are listed and a bad schedule is refused with its reason."""

import pytest
from django.contrib.auth import get_user_model
from django.test import Client

from maps.models import Station
from orders import services
from orders.models import OrderEvent, RecurringOrder, TransportOrder
from tests.factories import VehicleFactory


@pytest.fixture
def boss(db) -> Client:
    client = Client()
    client.force_login(get_user_model().objects.create_superuser("boss", password="x"))
    return client


def new_order() -> TransportOrder:
    return services.create_transport_order(
        source=Station.objects.get(station_id="PICK-1"),
        destination=Station.objects.get(station_id="DROP-1"),
    )


def act(client: Client, action: str, *orders: TransportOrder) -> None:
    response = client.post(
        "/admin/orders/transportorder/",
        {"action": action, "_selected_action": [o.pk for o in orders]},
    )
    assert response.status_code == 302


def test_actions_go_through_the_services(boss, demo_map) -> None:
    order, other = new_order(), new_order()

    act(boss, "raise_priority", order)
    act(boss, "lower_priority", other)
    act(boss, "cancel_orders", other)

    order.refresh_from_db()
    other.refresh_from_db()
    assert (order.priority, other.priority, other.status) == (10, -10, "CANCELLED")
    assert other.events.filter(kind=OrderEvent.Kind.CANCELLED).get().detail["by"] == "boss"


def test_editing_the_intended_vehicle_reassigns_through_the_service(boss, demo_map) -> None:
    first = VehicleFactory(last_node_id="A1.3")
    wanted = VehicleFactory(last_node_id="A5.0")
    order = new_order()
    services.dispatch_pending_orders()
    order.refresh_from_db()
    assert order.vehicle == first

    form = {
        "intended_vehicle": wanted.pk,
        "priority": order.priority,
        "load_id": "",
        "load_type": order.load_type,
        "external_ref": "",
        "metadata": "{}",
        "earliest_start_0": "",
        "earliest_start_1": "",
        "deadline_0": "",
        "deadline_1": "",
        "steps-TOTAL_FORMS": "0",
        "steps-INITIAL_FORMS": "0",
        "events-TOTAL_FORMS": "0",
        "events-INITIAL_FORMS": "0",
    }
    response = boss.post(f"/admin/orders/transportorder/{order.pk}/change/", form)

    errors = response.context["adminform"].form.errors if response.status_code == 200 else None
    assert response.status_code == 302, errors
    order.refresh_from_db()
    assert (order.status, order.vehicle, order.intended_vehicle) == ("NEW", None, wanted)
    assert order.events.filter(kind=OrderEvent.Kind.REQUEUED).exists()


def test_recurring_orders_and_sequences_in_admin(boss, demo_map) -> None:
    form = {
        "name": "A to B",
        "is_active": "on",
        "map": demo_map.pk,
        "steps": '[{"station": "PICK-1", "operation": "PICK"}, '
        '{"station": "NOPE", "operation": "DROP"}]',
        "priority": "0",
        "load_type": "EPAL",
        "interval_minutes": "15",
        "weekdays": "[0, 1, 2, 3, 4]",
        "window_start": "06:00",
        "window_end": "22:00",
        "runs-TOTAL_FORMS": "0",
        "runs-INITIAL_FORMS": "0",
    }

    refused = boss.post("/admin/orders/recurringorder/add/", form)
    saved = boss.post(
        "/admin/orders/recurringorder/add/",
        {**form, "steps": form["steps"].replace("NOPE", "DROP-2")},
    )

    assert "no station &#x27;NOPE&#x27; on map demo" in refused.content.decode()
    assert saved.status_code == 302
    assert RecurringOrder.objects.get().created_by.username == "boss"
    assert boss.get("/admin/orders/recurringorder/").status_code == 200
    assert boss.get("/admin/orders/ordersequence/").status_code == 200
