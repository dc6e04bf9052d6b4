"""Webhooks: subscriptions, recording deliveries with the change they report, and sending them.

Services only write delivery rows (in the caller's transaction) and enqueue a Celery task after
commit; the HTTP request happens in that task, with timeouts, so a dead or slow endpoint never
holds up dispatch or an API request. Each attempt is logged; failures are retried with
exponential backoff by the periodic sweep, which also sends deliveries whose task was lost.
"""

import json
import logging
import secrets
import time
import urllib.error
import urllib.request
import uuid
from collections.abc import Callable, Iterable, Iterator
from contextlib import contextmanager
from contextvars import ContextVar
from dataclasses import dataclass
from datetime import datetime, timedelta
from functools import partial
from typing import Any

from django.db import transaction
from django.db.models import F
from django.utils import timezone

from fleet.exceptions import InvalidRequestError
from orders import selectors
from orders.conf import setting
from orders.models import (
    IntegrationClient,
    TransportOrder,
    WebhookAttempt,
    WebhookDelivery,
    WebhookSubscription,
)
from orders.models.webhooks import EVENT_TYPES
from orders.signing import SIGNATURE_HEADER, sign

logger = logging.getLogger(__name__)
Status = WebhookDelivery.Status
USER_AGENT = "open-fleet-webhooks/1"
_FAMILIES = {event.split(".", 1)[0] + ".*" for event in EVENT_TYPES}


def create_webhook_subscription(
    *,
    client: IntegrationClient,
    url: str,
    events: list[str],
    description: str = "",
    own_orders_only: bool = False,
) -> WebhookSubscription:
    """Subscribe `client` to `events` at `url` (with `own_orders_only`, order events only for
    orders the client created); the signing secret is generated here."""
    unknown = sorted(set(events) - set(EVENT_TYPES) - _FAMILIES - {"*"})
    if unknown:
        raise InvalidRequestError(f"unknown event types: {', '.join(unknown)}")
    if not events:
        raise InvalidRequestError("subscribe to at least one event type")
    return WebhookSubscription.objects.create(
        client=client,
        url=url,
        events=sorted(set(events)),
        description=description,
        own_orders_only=own_orders_only,
        secret="whsec_" + secrets.token_urlsafe(32),
    )


def delete_webhook_subscription(*, subscription: WebhookSubscription) -> None:
    """Remove a subscription together with its delivery log."""
    subscription.delete()


@transaction.atomic
def ping_webhook_subscription(*, subscription: WebhookSubscription) -> WebhookDelivery:
    """Queue a `ping` event to one subscription, so a client can test its endpoint."""
    return _create_deliveries([subscription], "ping", {"subscription": subscription.pk})[0]


def emit_event(*, event_type: str, data: Callable[[], dict[str, Any]]) -> int:
    """Record a delivery of `event_type` for each subscription that wants it; send after commit.

    `data` is called only when someone subscribed, so an event costs one query when nobody
    listens. Call inside the transaction of the change the event reports.
    """
    wanted = _subscribers(event_type)
    if not wanted:
        return 0
    return len(_create_deliveries(wanted, event_type, data()))


def emit_order_event(*, order_id: int, event_type: str, detail: dict[str, Any]) -> int:
    """Like `emit_event` for an order's timeline entry; the payload holds the whole order as it is
    now. Subscriptions with `own_orders_only` get only the orders their client created."""
    wanted = _subscribers(event_type)
    if not wanted:
        return 0
    order = (
        TransportOrder.objects.select_related("source", "destination", "vehicle")
        .prefetch_related("steps__station")
        .get(pk=order_id)
    )
    wanted = [s for s in wanted if not s.own_orders_only or s.client.user_id == order.created_by_id]
    if not wanted:
        return 0
    data = {"order": order_payload(order), "detail": detail}
    return len(_create_deliveries(wanted, event_type, data))


def order_payload(order: TransportOrder) -> dict[str, Any]:
    """An order as webhook bodies carry it (the API's fields, without the timeline)."""
    return {
        "id": order.pk,
        "external_ref": order.external_ref,
        "status": order.status,
        "source": order.source.station_id,
        "destination": order.destination.station_id,
        "steps": [
            {
                "index": step.index,
                "station": step.station.station_id,
                "operation": step.operation,
                "action_type": step.action_type,
                "finished_at": step.finished_at,
            }
            for step in order.steps.all()
        ],
        "metadata": order.metadata,
        "vehicle": order.vehicle.serial_number if order.vehicle else None,
        "priority": order.priority,
        "load_id": order.load_id,
        "load_type": order.load_type,
        "earliest_start": order.earliest_start,
        "deadline": order.deadline,
        "failure_reason": order.failure_reason,
        "cancel_requested": order.cancel_requested,
        "created_at": order.created_at,
        "assigned_at": order.assigned_at,
        "started_at": order.started_at,
        "finished_at": order.finished_at,
    }


_snapshot: ContextVar[list[WebhookSubscription] | None] = ContextVar(
    "webhook_subscriptions", default=None
)


@contextmanager
def subscriptions_read_once() -> Iterator[None]:
    """Within the block (one dispatch cycle, say), read the active subscriptions only once:
    a cycle of 200 assignments emits 400 events, which otherwise query them 400 times."""
    token = _snapshot.set(selectors.list_active_subscriptions())
    try:
        yield
    finally:
        _snapshot.reset(token)


def active_subscriptions() -> list[WebhookSubscription]:
    """The active subscriptions: those read for the enclosing `subscriptions_read_once` block,
    else read now."""
    active = _snapshot.get()
    return selectors.list_active_subscriptions() if active is None else active


def _subscribers(event_type: str) -> list[WebhookSubscription]:
    return [s for s in active_subscriptions() if s.wants(event_type)]


def _create_deliveries(
    subscriptions: Iterable[WebhookSubscription], event_type: str, data: dict[str, Any]
) -> list[WebhookDelivery]:
    event_id, now = uuid.uuid4(), timezone.now()
    envelope = {"id": str(event_id), "type": event_type, "created_at": now, "data": data}
    deliveries = WebhookDelivery.objects.bulk_create(
        [
            WebhookDelivery(
                subscription=subscription,
                event_id=event_id,
                event_type=event_type,
                payload=envelope,
                next_attempt_at=now,
            )
            for subscription in subscriptions
        ]
    )
    transaction.on_commit(partial(_enqueue, [d.pk for d in deliveries]), robust=True)
    return deliveries


def _enqueue(delivery_ids: list[int]) -> None:
    from orders.tasks import deliver_webhook_task

    for delivery_id in delivery_ids:
        deliver_webhook_task.delay(delivery_id)


def retry_webhook_deliveries(*, delivery_ids: list[int]) -> int:
    """Send these deliveries again now, with a fresh series of attempts (from the admin)."""
    count = WebhookDelivery.objects.filter(pk__in=delivery_ids).update(
        status=Status.PENDING, next_attempt_at=timezone.now(), attempts=0
    )
    transaction.on_commit(partial(_enqueue, list(delivery_ids)), robust=True)
    return count


def enqueue_due_webhook_deliveries(*, now: datetime | None = None, limit: int = 500) -> int:
    """Queue a send for every pending delivery that is due (retries, and sends whose task was
    lost); run periodically. A delivery queued twice is still sent once (see the claim)."""
    due = selectors.list_due_webhook_deliveries(now=now or timezone.now(), limit=limit)
    _enqueue(due)
    return len(due)


@dataclass(frozen=True)
class _Answer:
    status_code: int | None
    excerpt: str
    error: str
    duration_ms: int


def attempt_webhook_delivery(*, delivery_id: int, now: datetime | None = None) -> bool:
    """Send one due delivery once, log the attempt, and schedule a retry or give up.

    The delivery is claimed first with a conditional update (pending, due, then pushed past the
    time one attempt can take), so concurrent tasks for the same delivery send it once. Runs
    outside any transaction: no lock is held while waiting for the endpoint. Returns whether an
    attempt was made.
    """
    now = now or timezone.now()
    timeout = float(setting("WEBHOOK_TIMEOUT"))
    claimed = WebhookDelivery.objects.filter(
        pk=delivery_id, status=Status.PENDING, next_attempt_at__lte=now
    ).update(next_attempt_at=now + timedelta(seconds=3 * timeout + 30), attempts=F("attempts") + 1)
    if not claimed:
        return False
    delivery = WebhookDelivery.objects.select_related("subscription__client").get(pk=delivery_id)
    subscription = delivery.subscription
    if not (subscription.is_active and subscription.client.is_active):
        answer = _Answer(None, "", "subscription disabled", 0)
    else:
        answer = _post(subscription, delivery, timeout)
    WebhookAttempt.objects.create(
        delivery=delivery,
        status_code=answer.status_code,
        response_excerpt=answer.excerpt,
        error=answer.error,
        duration_ms=answer.duration_ms,
    )
    _settle(delivery, answer, now)
    return True


def _settle(delivery: WebhookDelivery, answer: _Answer, now: datetime) -> None:
    if answer.status_code is not None and 200 <= answer.status_code < 300:
        delivery.status, delivery.delivered_at = Status.DELIVERED, timezone.now()
    elif delivery.attempts >= int(setting("WEBHOOK_MAX_ATTEMPTS")) or answer.error == (
        "subscription disabled"
    ):
        delivery.status = Status.FAILED
    else:
        delivery.next_attempt_at = now + timedelta(seconds=retry_delay(delivery.attempts))
    delivery.save(update_fields=["status", "delivered_at", "next_attempt_at"])


def retry_delay(attempts: int) -> float:
    """Seconds to wait after `attempts` failed attempts: base × 2^(attempts-1), capped."""
    base, cap = float(setting("WEBHOOK_RETRY_BASE")), float(setting("WEBHOOK_RETRY_CAP"))
    return float(min(cap, base * 2 ** max(0, attempts - 1)))


class _NoRedirects(urllib.request.HTTPRedirectHandler):
    """A redirect is an answer like any other non-2xx: logged and retried, never followed."""

    def redirect_request(self, *args: Any, **kwargs: Any) -> None:
        return None


_opener = urllib.request.build_opener(_NoRedirects)


def _post(subscription: WebhookSubscription, delivery: WebhookDelivery, timeout: float) -> _Answer:
    body = json.dumps(delivery.payload, separators=(",", ":"), sort_keys=True).encode()
    request = urllib.request.Request(  # noqa: S310 (URLField allows http and https only)
        subscription.url,
        data=body,
        method="POST",
        headers={
            "Content-Type": "application/json",
            "User-Agent": USER_AGENT,
            "X-Fleet-Event": delivery.event_type,
            "X-Fleet-Event-Id": str(delivery.event_id),
            "X-Fleet-Delivery": str(delivery.pk),
            SIGNATURE_HEADER: sign(subscription.secret, body, int(time.time())),
        },
    )
    started = time.monotonic()
    try:
        with _opener.open(request, timeout=timeout) as response:
            status, text = response.status, response.read(2000)
    except urllib.error.HTTPError as error:
        status, text = error.code, _read_quietly(error)
    except (OSError, ValueError) as error:  # refused, DNS, timeout, TLS, bad URL
        cause: BaseException = error
        if isinstance(error, urllib.error.URLError) and isinstance(error.reason, Exception):
            cause = error.reason
        elapsed = int((time.monotonic() - started) * 1000)
        return _Answer(None, "", f"{type(cause).__name__}: {cause}"[:300], elapsed)
    elapsed = int((time.monotonic() - started) * 1000)
    return _Answer(status, text.decode("utf-8", "replace")[:500], "", elapsed)


def _read_quietly(error: urllib.error.HTTPError) -> bytes:
    try:
        return error.read(2000)
    except OSError:
        return b""


def prune_webhook_deliveries(*, now: datetime | None = None) -> int:
    """Delete finished deliveries (and their attempt logs) older than WEBHOOK_LOG_DAYS."""
    cutoff = (now or timezone.now()) - timedelta(days=int(setting("WEBHOOK_LOG_DAYS")))
    deleted, _ = WebhookDelivery.objects.filter(
        created_at__lt=cutoff, status__in=[Status.DELIVERED, Status.FAILED]
    ).delete()
    return deleted
