"""Webhooks against a real HTTP server on 127.0.0.1, with Celery eager."""

import json
import time
from datetime import timedelta

import pytest
from django.utils import timezone

from orders import services
from orders.models import WebhookDelivery, WebhookSubscription
from orders.signing import verify
from orders.tasks import deliver_due_webhooks_task, prune_task
from tests.factories import VehicleFactory
from tests.orders.webhook_server import Endpoint, webhook_endpoint

Status = WebhookDelivery.Status


@pytest.fixture
def endpoint():
    with webhook_endpoint() as endpoint:
        yield endpoint


@pytest.fixture
def subscription(erp, endpoint: Endpoint) -> WebhookSubscription:
    return services.create_webhook_subscription(client=erp, url=endpoint.url, events=["*"])


def create_order(api, django_capture_on_commit_callbacks, **body) -> dict:
    with django_capture_on_commit_callbacks(execute=True):
        response = api.post(
            "/api/v1/orders/", {"source": "PICK-1", "destination": "DROP-1", **body}, format="json"
        )
    assert response.status_code == 201, response.content
    return response.json()


def events(endpoint: Endpoint) -> list[str]:
    return [json.loads(r.body)["type"] for r in endpoint.received]


def test_order_events_are_delivered_signed(
    api, demo_map, subscription, endpoint, django_capture_on_commit_callbacks
) -> None:
    VehicleFactory(last_node_id="A1.3")

    order = create_order(api, django_capture_on_commit_callbacks, external_ref="SO-7")
    with django_capture_on_commit_callbacks(execute=True):
        services.mark_order_started(order_id=order["id"])
        services.mark_step_reached(order_id=order["id"], step="pick", node_id="S-PICK-1")
        services.mark_order_finished(order_id=order["id"])

    assert events(endpoint) == [
        "order.created",
        "order.assigned",
        "vehicle.order_assigned",
        "order.started",
        "order.step_reached",
        "order.finished",
        "vehicle.order_finished",
    ]
    first = endpoint.received[0]
    body = json.loads(first.body)
    assert body["data"]["order"]["external_ref"] == "SO-7"
    assert body["data"]["order"]["id"] == order["id"]
    assert first.headers["Content-Type"] == "application/json"
    assert first.headers["X-Fleet-Event"] == "order.created"
    assert first.headers["X-Fleet-Event-Id"] == body["id"]
    assert verify(subscription.secret, first.body, first.headers["X-Fleet-Signature"])
    assert not verify("wrong-secret", first.body, first.headers["X-Fleet-Signature"])
    assert not verify(subscription.secret, first.body + b" ", first.headers["X-Fleet-Signature"])
    delivery = WebhookDelivery.objects.filter(event_type="order.created").get()
    assert (delivery.status, delivery.attempts) == (Status.DELIVERED, 1)
    assert delivery.log.get().status_code == 200
    assert json.loads(endpoint.received[4].body)["data"]["detail"] == {
        "step": "pick",
        "node": "S-PICK-1",
        "index": 0,
    }


def test_cancel_failure_and_requeue_events(
    api, demo_map, subscription, endpoint, django_capture_on_commit_callbacks
) -> None:
    first = create_order(api, django_capture_on_commit_callbacks)
    second = create_order(api, django_capture_on_commit_callbacks)
    with django_capture_on_commit_callbacks(execute=True):
        api.post(f"/api/v1/orders/{first['id']}/cancel/", {}, format="json")
        services.mark_order_failed(order_id=second["id"], reason="vehicle broke")

    assert events(endpoint) == ["order.created", "order.created", "order.cancelled", "order.failed"]
    assert json.loads(endpoint.received[-1].body)["data"]["order"]["failure_reason"] == (
        "vehicle broke"
    )


def test_subscriptions_get_only_what_they_asked_for(
    api, demo_map, erp, endpoint, django_capture_on_commit_callbacks
) -> None:
    services.create_webhook_subscription(client=erp, url=endpoint.url, events=["order.cancelled"])
    other = services.create_integration_client(name="wms")
    services.create_webhook_subscription(
        client=other, url=endpoint.url + "/wms", events=["order.*"], own_orders_only=True
    )

    order = create_order(api, django_capture_on_commit_callbacks)
    with django_capture_on_commit_callbacks(execute=True):
        api.post(f"/api/v1/orders/{order['id']}/cancel/", {}, format="json")

    assert [(r.path, json.loads(r.body)["type"]) for r in endpoint.received] == [
        ("/hook", "order.cancelled")
    ]


def test_failed_attempts_are_logged_and_retried_with_backoff(
    api, demo_map, subscription, endpoint, django_capture_on_commit_callbacks, settings
) -> None:
    settings.FLEET_ORDERS = {"WEBHOOK_RETRY_BASE": 10.0, "WEBHOOK_MAX_ATTEMPTS": 3}
    endpoint.answers = [(500, 0.0), (503, 0.0), (500, 0.0)]

    create_order(api, django_capture_on_commit_callbacks)
    delivery = WebhookDelivery.objects.get()
    first_retry_at = delivery.next_attempt_at
    assert deliver_due_webhooks_task.delay().get() == 0  # not due yet
    for _ in range(2):
        WebhookDelivery.objects.update(next_attempt_at=timezone.now())
        deliver_due_webhooks_task.delay()

    delivery.refresh_from_db()
    log = list(delivery.log.order_by("at"))
    assert [attempt.status_code for attempt in log] == [500, 503, 500]
    assert log[0].response_excerpt == "answer 500"
    assert (delivery.status, delivery.attempts) == (Status.FAILED, 3)
    assert 9 <= (first_retry_at - log[0].at).total_seconds() <= 11
    assert [services.webhooks.retry_delay(n) for n in (1, 2, 3)] == [10.0, 20.0, 40.0]


def test_a_retry_that_succeeds_marks_the_delivery_delivered(
    api, demo_map, subscription, endpoint, django_capture_on_commit_callbacks
) -> None:
    endpoint.answers = [(502, 0.0)]

    create_order(api, django_capture_on_commit_callbacks)
    WebhookDelivery.objects.update(next_attempt_at=timezone.now())
    deliver_due_webhooks_task.delay()

    delivery = WebhookDelivery.objects.get()
    assert (delivery.status, delivery.attempts) == (Status.DELIVERED, 2)
    assert len(endpoint.received) == 2


def test_a_dead_or_slow_endpoint_never_fails_or_blocks_the_caller(
    api, demo_map, erp, endpoint, django_capture_on_commit_callbacks, settings
) -> None:
    settings.FLEET_ORDERS = {"WEBHOOK_TIMEOUT": 0.3}
    endpoint.answers = [(200, 2.0)]  # answers after 2 s: too late
    services.create_webhook_subscription(client=erp, url=endpoint.url, events=["order.created"])
    services.create_webhook_subscription(
        client=erp, url="http://127.0.0.1:9/refused", events=["order.created"]
    )

    started = time.monotonic()
    create_order(api, django_capture_on_commit_callbacks)
    elapsed = time.monotonic() - started

    assert elapsed < 1.5
    errors = sorted(d.log.get().error.split(":")[0] for d in WebhookDelivery.objects.all())
    assert errors == ["ConnectionRefusedError", "TimeoutError"]
    assert set(WebhookDelivery.objects.values_list("status", flat=True)) == {Status.PENDING}


def test_a_delivery_is_sent_once_even_when_queued_twice(
    api, demo_map, subscription, endpoint, django_capture_on_commit_callbacks
) -> None:
    create_order(api, django_capture_on_commit_callbacks)
    delivery = WebhookDelivery.objects.get()

    assert not services.attempt_webhook_delivery(delivery_id=delivery.pk)
    assert len(endpoint.received) == 1


def test_a_disabled_subscription_fails_its_pending_deliveries(
    api, demo_map, subscription, endpoint, django_capture_on_commit_callbacks
) -> None:
    with django_capture_on_commit_callbacks(execute=False):
        api.post("/api/v1/orders/", {"source": "PICK-1", "destination": "DROP-1"}, format="json")
    subscription.is_active = False
    subscription.save()

    deliver_due_webhooks_task.delay()

    delivery = WebhookDelivery.objects.get()
    assert (delivery.status, delivery.log.get().error) == (Status.FAILED, "subscription disabled")
    assert endpoint.received == []


def test_vehicle_commands_are_events_too(erp, endpoint, django_capture_on_commit_callbacks) -> None:
    services.create_webhook_subscription(client=erp, url=endpoint.url, events=["vehicle.*"])
    vehicle = VehicleFactory()

    with django_capture_on_commit_callbacks(execute=True):
        services.pause_vehicle(vehicle=vehicle)

    body = json.loads(endpoint.received[0].body)
    assert body["type"] == "vehicle.command_queued"
    assert body["data"]["command"]["kind"] == "vehicle.pause"
    assert body["data"]["vehicle"]["serial_number"] == vehicle.serial_number


def test_finished_deliveries_are_pruned_after_the_log_period(
    api, demo_map, subscription, endpoint, django_capture_on_commit_callbacks
) -> None:
    create_order(api, django_capture_on_commit_callbacks)
    WebhookDelivery.objects.update(created_at=timezone.now() - timedelta(days=31))

    assert prune_task.delay().get() == 2  # the delivery and its attempt
    assert not WebhookDelivery.objects.exists()


def test_subscription_api_for_the_calling_client(
    api, erp, endpoint, demo_map, django_capture_on_commit_callbacks
) -> None:
    created = api.post(
        "/api/v1/webhooks/",
        {"url": endpoint.url, "events": ["order.finished", "order.failed"]},
        format="json",
    )
    subscription_id = created.json()["id"]

    listed = api.get("/api/v1/webhooks/").json()
    shown = api.get(f"/api/v1/webhooks/{subscription_id}/").json()
    with django_capture_on_commit_callbacks(execute=True):
        pinged = api.post(f"/api/v1/webhooks/{subscription_id}/ping/")
    bad = api.post(
        "/api/v1/webhooks/", {"url": endpoint.url, "events": ["order.lost"]}, format="json"
    )
    deleted = api.delete(f"/api/v1/webhooks/{subscription_id}/")

    assert created.status_code == 201
    assert created.json()["secret"].startswith("whsec_")
    assert [s["id"] for s in listed] == [subscription_id]
    assert "secret" not in shown
    assert shown["events"] == ["order.failed", "order.finished"]
    assert pinged.status_code == 202
    assert json.loads(endpoint.received[0].body)["type"] == "ping"
    assert bad.status_code == 422
    assert deleted.status_code == 204
    assert not WebhookSubscription.objects.exists()


def test_subscriptions_of_other_clients_are_invisible(api, demo_map, endpoint) -> None:
    other = services.create_integration_client(name="wms")
    theirs = services.create_webhook_subscription(client=other, url=endpoint.url, events=["*"])

    assert api.get(f"/api/v1/webhooks/{theirs.pk}/").status_code == 404
    assert api.delete(f"/api/v1/webhooks/{theirs.pk}/").status_code == 404
    assert api.get("/api/v1/webhooks/").json() == []


def test_users_that_are_not_clients_cannot_subscribe(db, demo_map) -> None:
    from django.contrib.auth import get_user_model
    from rest_framework.test import APIClient

    staff = APIClient()
    staff.force_authenticate(get_user_model().objects.create_user("staff"))

    assert staff.get("/api/v1/webhooks/").status_code == 403


def test_a_dispatch_cycle_reads_the_subscriptions_once_however_many_it_assigns(
    station, subscription
) -> None:
    from django.db import connection
    from django.test.utils import CaptureQueriesContext

    for node in ("A0.3", "A1.3", "A2.3"):
        VehicleFactory(last_node_id=node)
    for pick in ("PICK-1", "PICK-2", "PICK-3"):
        services.create_transport_order(source=station(pick), destination=station("DROP-1"))
    WebhookDelivery.objects.all().delete()

    with CaptureQueriesContext(connection) as queries:
        assigned = services.dispatch_pending_orders()

    assert len(assigned) == 3
    reads = [q["sql"] for q in queries if 'FROM "orders_webhooksubscription"' in q["sql"]]
    assert len(reads) == 1
    # ...and every assignment still produced its two events for the subscriber.
    assert WebhookDelivery.objects.filter(subscription=subscription).count() == 6
