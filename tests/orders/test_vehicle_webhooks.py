"""Vehicle-state webhooks: connection, mode, errors from control's flush; orders assigned and
finished; delivered signed to a real HTTP server like order events."""

import json

import pytest

from maps.models import Station
from orders import services
from orders.models import WebhookDelivery
from orders.signing import verify
from robots.models import Vehicle
from tests.factories import VehicleFactory
from tests.orders.webhook_server import Endpoint, webhook_endpoint


@pytest.fixture
def endpoint():
    with webhook_endpoint() as endpoint:
        yield endpoint


def vehicle_bodies(endpoint: Endpoint) -> list[tuple[str, dict]]:
    bodies = [json.loads(r.body) for r in endpoint.received]
    return [(b["type"], b["data"]["detail"]) for b in bodies if b["type"].startswith("vehicle.")]


def test_connection_mode_and_new_errors_are_delivered_signed(
    erp, endpoint, django_capture_on_commit_callbacks
) -> None:
    subscription = services.create_webhook_subscription(
        client=erp, url=endpoint.url, events=["vehicle.*"]
    )
    vehicle = VehicleFactory(operating_mode="AUTOMATIC", errors=[])
    error = {"errorType": "loadCollision", "errorLevel": "WARNING"}
    rows = [
        {
            "pk": vehicle.pk,
            "connection": "CONNECTIONBROKEN",
            "operating_mode": "MANUAL",
            "errors": [error],
        },
    ]

    with django_capture_on_commit_callbacks(execute=True):
        emitted = services.emit_vehicle_changes(snapshots=rows)
    Vehicle.objects.filter(pk=vehicle.pk).update(
        connection="CONNECTIONBROKEN", operating_mode="MANUAL", errors=[error]
    )
    with django_capture_on_commit_callbacks(execute=True):
        unchanged = services.emit_vehicle_changes(snapshots=rows)

    assert (emitted, unchanged) == (3, 0)
    assert vehicle_bodies(endpoint) == [
        ("vehicle.connection_changed", {"old": "ONLINE", "new": "CONNECTIONBROKEN"}),
        ("vehicle.mode_changed", {"old": "AUTOMATIC", "new": "MANUAL"}),
        ("vehicle.error", {"errors": [error]}),
    ]
    first = endpoint.received[0]
    assert json.loads(first.body)["data"]["vehicle"]["serial_number"] == vehicle.serial_number
    assert verify(subscription.secret, first.body, first.headers["X-Fleet-Signature"])


def test_without_vehicle_subscribers_a_flush_records_nothing(erp, endpoint) -> None:
    services.create_webhook_subscription(client=erp, url=endpoint.url, events=["order.*"])
    vehicle = VehicleFactory()

    emitted = services.emit_vehicle_changes(snapshots=[{"pk": vehicle.pk, "connection": "OFFLINE"}])

    assert emitted == 0
    assert not WebhookDelivery.objects.exists()


def test_order_assigned_and_finished_reach_vehicle_subscribers(
    erp, endpoint, demo_map, django_capture_on_commit_callbacks, sent_commands
) -> None:
    services.create_webhook_subscription(
        client=erp,
        url=endpoint.url,
        events=["vehicle.order_assigned", "vehicle.order_finished"],
    )
    vehicle = VehicleFactory(last_node_id="A1.3")

    with django_capture_on_commit_callbacks(execute=True):
        order = services.create_transport_order(
            source=Station.objects.get(station_id="PICK-1"),
            destination=Station.objects.get(station_id="DROP-1"),
        )
        services.dispatch_pending_orders()
    with django_capture_on_commit_callbacks(execute=True):
        services.mark_order_started(order_id=order.pk)
        services.mark_order_finished(order_id=order.pk)

    assert vehicle_bodies(endpoint) == [
        ("vehicle.order_assigned", {"order": order.pk}),
        ("vehicle.order_finished", {"order": order.pk}),
    ]
    body = json.loads(endpoint.received[0].body)
    assert body["data"]["vehicle"]["id"] == vehicle.pk


def test_a_broken_flush_hook_never_raises(db, monkeypatch, caplog) -> None:
    def broken() -> list:
        raise RuntimeError("database hiccup")

    monkeypatch.setattr("orders.selectors.list_active_subscriptions", broken)

    assert services.emit_vehicle_changes(snapshots=[{"pk": 1, "connection": "OFFLINE"}]) == 0
    assert "could not record the events of a flush" in caplog.text
    assert "database hiccup" in caplog.text
