"""Writes of transport orders: creation, changes by the ERP, progress from control, cancelling."""

from datetime import datetime

from django.contrib.auth.base_user import AbstractBaseUser
from django.contrib.auth.models import AnonymousUser, User
from django.db import transaction
from django.utils import timezone

from fleet.control_queue import send_command
from fleet.exceptions import DomainError, InvalidRequestError
from fleet.realtime import LIVE_GROUP, broadcast_on_commit
from maps.models import Station
from maps.selectors import load_graph
from orders.models import OrderEvent, TransportOrder
from orders.services.events import dispatch_on_commit, record, transition, who
from traffic import NoRouteError

Status = TransportOrder.Status
Kind = OrderEvent.Kind


@transaction.atomic
def create_transport_order(
    *,
    source: Station,
    destination: Station,
    priority: int = 0,
    load_id: str = "",
    load_type: str = "EPAL",
    external_ref: str = "",
    earliest_start: datetime | None = None,
    deadline: datetime | None = None,
    created_by: AbstractBaseUser | AnonymousUser | None = None,
) -> TransportOrder:
    """Queue a new transport order and trigger dispatch once it is committed.

    Both stations must be on the same map, the destination reachable from the source, and a
    deadline later than the earliest start.
    """
    if source.pk == destination.pk:
        raise InvalidRequestError("source and destination are the same station")
    if source.map_id != destination.map_id:
        raise InvalidRequestError("source and destination are on different maps")
    _check_window(earliest_start, deadline)
    try:
        load_graph(map=source.map).shortest_path(source.node.node_id, destination.node.node_id)
    except NoRouteError as exc:
        raise InvalidRequestError(f"destination not reachable from source: {exc}") from None
    order = TransportOrder.objects.create(
        source=source,
        destination=destination,
        priority=priority,
        load_id=load_id,
        load_type=load_type,
        external_ref=external_ref,
        earliest_start=earliest_start,
        deadline=deadline,
        created_by=created_by if isinstance(created_by, User) else None,
    )
    record(order.pk, Kind.CREATED, by=who(created_by))
    broadcast_on_commit(LIVE_GROUP, "orders.changed", {"order": order.pk})
    dispatch_on_commit()
    return order


@transaction.atomic
def update_order_priority(
    *,
    order: TransportOrder,
    priority: int,
    deadline: datetime | None = None,
    change_deadline: bool = False,
    by: AbstractBaseUser | AnonymousUser | None = None,
) -> TransportOrder:
    """Change an open order's priority and, with `change_deadline`, its deadline (None clears it).

    Dispatch uses both for orders still waiting; for an order a vehicle already has they are
    kept for the record and the reports.
    """
    order = TransportOrder.objects.select_for_update().get(pk=order.pk)
    if not order.is_open:
        raise DomainError(f"order {order.pk} is {order.status} and can no longer change")
    changes: dict[str, object] = {}
    if priority != order.priority:
        changes["priority"] = [order.priority, priority]
        order.priority = priority
    if change_deadline and deadline != order.deadline:
        _check_window(order.earliest_start, deadline)
        changes["deadline"] = [_iso(order.deadline), _iso(deadline)]
        order.deadline = deadline
    if changes:
        order.save(update_fields=["priority", "deadline", "updated_at"])
        record(order.pk, Kind.UPDATED, by=who(by), **changes)
        broadcast_on_commit(LIVE_GROUP, "orders.changed", {"order": order.pk})
        if order.status == Status.NEW:
            dispatch_on_commit()
    return order


@transaction.atomic
def cancel_transport_order(
    *, order: TransportOrder, reason: str = "", by: AbstractBaseUser | AnonymousUser | None = None
) -> TransportOrder:
    """Cancel an order: at once if no vehicle has it yet, else ask `control` to stop the vehicle."""
    order = TransportOrder.objects.select_for_update().get(pk=order.pk)
    if not order.is_open:
        raise DomainError(f"order {order.pk} is {order.status} and cannot be cancelled")
    if order.status == Status.NEW:
        order.status, order.finished_at = Status.CANCELLED, timezone.now()
        order.save(update_fields=["status", "finished_at", "updated_at"])
        record(order.pk, Kind.CANCELLED, reason=reason, by=who(by))
    elif not order.cancel_requested:
        order.cancel_requested = True
        order.save(update_fields=["cancel_requested", "updated_at"])
        record(order.pk, Kind.CANCEL_REQUESTED, reason=reason, by=who(by))
        order_id = order.pk
        transaction.on_commit(lambda: send_command("order.cancel", order=order_id), robust=True)
    broadcast_on_commit(LIVE_GROUP, "orders.changed", {"order": order.pk})
    return order


@transaction.atomic
def mark_order_sent(*, order_id: int) -> None:
    """Control published the VDA 5050 order: from now on only the vehicle's state decides, and
    the reconciler never takes the order back. Idempotent (the first send counts)."""
    TransportOrder.objects.filter(pk=order_id, status=Status.ASSIGNED, sent_at__isnull=True).update(
        sent_at=timezone.now()
    )


@transaction.atomic
def mark_order_started(*, order_id: int) -> None:
    """The vehicle accepted the VDA 5050 order (control saw it in the vehicle's state)."""
    if transition(order_id, {Status.ASSIGNED}, Status.IN_PROGRESS, started_at=timezone.now()):
        record(order_id, Kind.STARTED)


@transaction.atomic
def mark_step_reached(*, order_id: int, step: str, node_id: str) -> None:
    """The vehicle finished the pick or drop action of the order at `node_id`."""
    record(order_id, Kind.STEP_REACHED, step=step, node=node_id)


@transaction.atomic
def mark_order_finished(*, order_id: int) -> None:
    """The vehicle drove the whole route and finished its actions."""
    if transition(
        order_id, set(TransportOrder.ACTIVE_STATUSES), Status.FINISHED, finished_at=timezone.now()
    ):
        record(order_id, Kind.FINISHED)
        dispatch_on_commit()


@transaction.atomic
def mark_order_failed(*, order_id: int, reason: str) -> None:
    """The order cannot complete (rejected by the vehicle, failed action, fatal error)."""
    if transition(
        order_id,
        set(TransportOrder.OPEN_STATUSES),
        Status.FAILED,
        finished_at=timezone.now(),
        failure_reason=reason[:2000],
    ):
        record(order_id, Kind.FAILED, reason=reason)
        dispatch_on_commit()


@transaction.atomic
def requeue_order(*, order_id: int, reason: str) -> None:
    """Give an assigned order back to dispatch: the vehicle could not start it as planned
    (it is no longer where the route begins). Orders already started are never requeued."""
    if transition(
        order_id,
        {Status.ASSIGNED},
        Status.NEW,
        vehicle=None,
        route=[],
        assigned_at=None,
        sent_at=None,
        dispatch_note="requeued: " + reason[:180],
    ):
        record(order_id, Kind.REQUEUED, reason=reason)
        dispatch_on_commit()


@transaction.atomic
def mark_order_cancelled(*, order_id: int) -> None:
    """The vehicle stopped after a cancel request (control confirmed cancelOrder finished)."""
    if transition(
        order_id, set(TransportOrder.OPEN_STATUSES), Status.CANCELLED, finished_at=timezone.now()
    ):
        record(order_id, Kind.CANCELLED)
        dispatch_on_commit()


def _check_window(earliest_start: datetime | None, deadline: datetime | None) -> None:
    if earliest_start and deadline and deadline <= earliest_start:
        raise InvalidRequestError("the deadline must be later than the earliest start")


def _iso(moment: datetime | None) -> str | None:
    return moment.isoformat() if moment else None
