"""Writes of transport orders: creation, changes by the ERP, progress from control, cancelling."""

from datetime import datetime
from typing import Any

from django.contrib.auth.base_user import AbstractBaseUser
from django.contrib.auth.models import AnonymousUser, User
from django.db import transaction
from django.db.models import Q
from django.utils import timezone

from fleet import audit
from fleet.control_queue import send_command
from fleet.exceptions import DomainError, InvalidRequestError
from fleet.realtime import LIVE_GROUP, broadcast_on_commit
from maps.models import Station, VehicleType
from orders.models import OrderEvent, OrderSequence, OrderStep, TransportOrder
from orders.services import floor
from orders.services.events import dispatch_on_commit, record, transition, who
from orders.services.steps import StepSpec, check_steps, pick_drop, save_steps
from orders.services.vehicle_events import emit_vehicle_order_event
from robots.models import Vehicle

Status = TransportOrder.Status
Kind = OrderEvent.Kind


@transaction.atomic
def create_transport_order(
    *,
    source: Station | None = None,
    destination: Station | None = None,
    steps: list[StepSpec] | None = None,
    priority: int = 0,
    load_id: str = "",
    load_type: str = "EPAL",
    external_ref: str = "",
    earliest_start: datetime | None = None,
    deadline: datetime | None = None,
    intended_vehicle: Vehicle | None = None,
    vehicle_type: VehicleType | None = None,
    metadata: dict[str, Any] | None = None,
    sequence: str = "",
    created_by: AbstractBaseUser | AnonymousUser | None = None,
) -> TransportOrder:
    """Queue a new transport order and trigger dispatch once it is committed.

    Either `steps` (multi-stop) or `source` and `destination` (pick there, drop here). All steps
    must be on one map, each reachable from the one before (for `vehicle_type` if given), and a
    deadline later than the earliest start. With `sequence` (the client's reference), the order
    joins that order sequence (created on first use) as its next order.
    """
    if steps is None:
        if source is None or destination is None:
            raise InvalidRequestError("give steps, or source and destination")
        if source.pk == destination.pk:
            raise InvalidRequestError("source and destination are the same station")
        if source.map_id != destination.map_id:
            raise InvalidRequestError("source and destination are on different maps")
        steps = pick_drop(source, destination)
    elif source is not None or destination is not None:
        raise InvalidRequestError("give steps or source and destination, not both")
    _check_window(earliest_start, deadline)
    check_steps(steps, vehicle_type=vehicle_type, intended_vehicle=intended_vehicle)
    chain, place = _join_sequence(sequence) if sequence else (None, None)
    order = TransportOrder.objects.create(
        sequence=chain,
        sequence_index=place,
        source=steps[0].station,
        destination=steps[-1].station,
        priority=priority,
        load_id=load_id,
        load_type=load_type,
        external_ref=external_ref,
        earliest_start=earliest_start,
        deadline=deadline,
        intended_vehicle=intended_vehicle,
        vehicle_type=vehicle_type,
        metadata=metadata or {},
        created_by=created_by if isinstance(created_by, User) else None,
    )
    save_steps(order.pk, steps)
    record(order.pk, Kind.CREATED, by=who(created_by))
    audit.record(
        "order.create",
        target_type="order",
        target_id=order.pk,
        detail={
            "steps": [[step.station.station_id, step.vda_action_type] for step in steps],
            "priority": priority,
            "external_ref": external_ref,
        },
    )
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
        audit.record("order.change", target_type="order", target_id=order.pk, detail=changes)
        broadcast_on_commit(LIVE_GROUP, "orders.changed", {"order": order.pk})
        if order.status == Status.NEW:
            dispatch_on_commit()
    return order


@transaction.atomic
def reassign_order(
    *,
    order: TransportOrder,
    vehicle: Vehicle | None,
    by: AbstractBaseUser | AnonymousUser | None = None,
) -> TransportOrder:
    """Make `vehicle` the only one allowed to do the order (None: any vehicle again) and give an
    assigned order back to dispatch. Only while no vehicle has received it: once control sent
    it, the vehicle is driving it and only cancelling stops it."""
    order = TransportOrder.objects.select_for_update().get(pk=order.pk)
    sent = order.sent_at is not None or order.status == Status.IN_PROGRESS
    if order.status not in (Status.NEW, Status.ASSIGNED) or sent:
        raise DomainError(
            f"order {order.pk} is {order.status}{' and sent to its vehicle' if sent else ''}; "
            "only waiting or unsent orders can be reassigned (cancel it instead)"
        )
    if vehicle is not None and order.source.map.map_id not in (vehicle.map_id, ""):
        raise InvalidRequestError(f"{vehicle} is not on map {order.source.map.map_id}")
    name = str(vehicle) if vehicle is not None else "any vehicle"
    previous = order.intended_vehicle_id
    TransportOrder.objects.filter(pk=order.pk).update(intended_vehicle=vehicle)
    if order.status == Status.ASSIGNED:
        if order.vehicle is not None and order.vehicle.order_id == order.vda_order_id:
            raise DomainError(f"{order.vehicle} already has order {order.pk}; cancel it instead")
        requeue = transition(
            order.pk,
            {Status.ASSIGNED},
            Status.NEW,
            where=Q(sent_at__isnull=True, started_at__isnull=True),
            vehicle=None,
            route=[],
            route_steps=[],
            assigned_at=None,
            dispatch_note=f"reassigned to {name}",
        )
        if requeue:
            record(order.pk, Kind.REQUEUED, reason=f"reassigned to {name}", by=who(by))
    elif previous != (vehicle.pk if vehicle else None):
        record(order.pk, Kind.UPDATED, intended_vehicle=name, by=who(by))
    audit.record("order.reassign", target_type="order", target_id=order.pk, detail={"to": name})
    broadcast_on_commit(LIVE_GROUP, "orders.changed", {"order": order.pk})
    dispatch_on_commit()
    order.refresh_from_db()
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
    audit.record("order.cancel", target_type="order", target_id=order.pk, detail={"reason": reason})
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
def mark_step_reached(*, order_id: int, step: str, node_id: str, index: int | None = None) -> None:
    """The vehicle reached step `index` (0-based) at `node_id` and finished its `step` action
    there. Recorded once per step; `index` None (an older control) means the order's first
    unfinished step of that action type."""
    steps = OrderStep.objects.filter(order_id=order_id, finished_at__isnull=True)
    if index is not None:
        steps = steps.filter(index=index)
    elif step in ("pick", "drop"):
        steps = steps.filter(operation=step.upper())
    else:
        steps = steps.filter(action_type=step)
    first = steps.order_by("index").first()
    if first is not None:
        OrderStep.objects.filter(pk=first.pk).update(finished_at=timezone.now())
        floor.on_step_finished(step=first)  # inventory follows picks and drops (issue 8)
        index = first.index
    elif OrderStep.objects.filter(order_id=order_id).exists():
        return  # already recorded (a resent state, a restarted control)
    detail: dict[str, Any] = {"step": step, "node": node_id}
    if index is not None:
        detail["index"] = index
    record(order_id, Kind.STEP_REACHED, **detail)
    broadcast_on_commit(LIVE_GROUP, "orders.changed", {"order": order_id})


@transaction.atomic
def mark_order_finished(*, order_id: int) -> None:
    """The vehicle drove the whole route and finished its actions."""
    if transition(
        order_id, set(TransportOrder.ACTIVE_STATUSES), Status.FINISHED, finished_at=timezone.now()
    ):
        record(order_id, Kind.FINISHED)
        vehicle = Vehicle.objects.filter(transport_orders=order_id).first()
        if vehicle is not None:
            emit_vehicle_order_event(
                event_type="vehicle.order_finished", vehicle=vehicle, order_id=order_id
            )
        floor.on_order_closed(order_id=order_id)
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
        floor.on_order_failed(order_id=order_id, reason=reason)
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
        route_steps=[],
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
        floor.on_order_closed(order_id=order_id)
        dispatch_on_commit()


def _join_sequence(reference: str) -> tuple[OrderSequence, int]:
    """The sequence `reference` (created if new, locked so concurrent joins queue up) and the
    place of the next order in it."""
    OrderSequence.objects.get_or_create(reference=reference)
    chain = OrderSequence.objects.select_for_update().get(reference=reference)
    return chain, TransportOrder.objects.filter(sequence=chain).count()


def _check_window(earliest_start: datetime | None, deadline: datetime | None) -> None:
    if earliest_start and deadline and deadline <= earliest_start:
        raise InvalidRequestError("the deadline must be later than the earliest start")


def _iso(moment: datetime | None) -> str | None:
    return moment.isoformat() if moment else None
