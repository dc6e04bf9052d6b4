"""The steps every write of a transport order shares: guarded status transitions, the timeline
entry, the webhook event, the live-page broadcast and waking dispatch, all after commit."""

from typing import Any

from django.contrib.auth.base_user import AbstractBaseUser
from django.contrib.auth.models import AnonymousUser
from django.db import transaction
from django.db.models import Q
from django.utils import timezone

from fleet.realtime import LIVE_GROUP, broadcast_on_commit
from orders.models import OrderEvent, TransportOrder
from orders.services import dispatch_queue
from orders.services.webhooks import emit_order_event

WEBHOOK_EVENT = {kind: f"order.{kind.lower()}" for kind in OrderEvent.Kind.values}


def transition(
    order_id: int, allowed: set[str], target: str, *, where: Q | None = None, **fields: Any
) -> bool:
    """Move the order to `target` if it is in one of the `allowed` statuses and matches `where`
    (one conditional UPDATE, so concurrent writers cannot both win). Returns whether it moved."""
    orders = TransportOrder.objects.filter(pk=order_id, status__in=allowed)
    if where is not None:
        orders = orders.filter(where)
    updated = orders.update(status=target, updated_at=timezone.now(), **fields)
    if updated:
        broadcast_on_commit(LIVE_GROUP, "orders.changed", {"order": order_id})
    return bool(updated)


def record(order_id: int, kind: str, **detail: Any) -> OrderEvent:
    """Add an entry to the order's timeline and report it to webhook subscribers."""
    event = OrderEvent.objects.create(order_id=order_id, kind=kind, detail=detail)
    emit_order_event(order_id=order_id, event_type=WEBHOOK_EVENT[kind], detail=detail)
    return event


def who(user: AbstractBaseUser | AnonymousUser | None) -> str:
    """How the timeline names the author of a change."""
    return str(user) if user is not None and user.is_authenticated else "system"


def dispatch_on_commit() -> None:
    """Ask for a dispatch cycle once the current transaction commits (coalesced with the other
    requests, see `dispatch_queue`). A failure there (the broker is down, say) is logged and never
    undoes or fails the caller: beat runs dispatch anyway."""
    transaction.on_commit(dispatch_queue.request_dispatch, robust=True)
