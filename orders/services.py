"""Writes of transport orders: creation, dispatch, progress from control, cancellation."""

import logging
from typing import Any

from django.contrib.auth.base_user import AbstractBaseUser
from django.contrib.auth.models import AnonymousUser, User
from django.db import IntegrityError, transaction
from django.utils import timezone

from fleet.control_queue import send_command
from fleet.exceptions import DomainError, InvalidRequestError
from fleet.realtime import LIVE_GROUP, broadcast_on_commit
from maps.models import Map, Station
from maps.selectors import load_graph
from orders import selectors
from orders.models import OrderEvent, TransportOrder
from robots.models import Vehicle
from traffic import NoRouteError, RoutingGraph

logger = logging.getLogger(__name__)
Status = TransportOrder.Status


@transaction.atomic
def create_transport_order(
    *,
    source: Station,
    destination: Station,
    priority: int = 0,
    load_id: str = "",
    load_type: str = "EPAL",
    external_ref: str = "",
    created_by: AbstractBaseUser | AnonymousUser | None = None,
) -> TransportOrder:
    """Queue a new transport order and trigger dispatch once it is committed.

    Both stations must be on the same map and the destination reachable from the source.
    """
    if source.pk == destination.pk:
        raise InvalidRequestError("source and destination are the same station")
    if source.map_id != destination.map_id:
        raise InvalidRequestError("source and destination are on different maps")
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
        created_by=created_by if isinstance(created_by, User) else None,
    )
    _record(order, OrderEvent.Kind.CREATED, by=_who(created_by))
    _on_commit_dispatch()
    return order


def dispatch_pending_orders() -> list[TransportOrder]:
    """Assign pending orders to the nearest idle vehicle by routing distance (greedy, by urgency).

    Safe to run concurrently: an order is claimed with a conditional update and the database's
    one-active-order-per-vehicle constraint rejects a vehicle that another run took first.
    """
    idle = selectors.list_idle_vehicles()
    graphs: dict[int, RoutingGraph] = {}
    assigned: list[TransportOrder] = []
    for order in selectors.list_pending_orders():
        if not idle:
            break
        layout = order.source.map
        graph = graphs.get(layout.pk) or graphs.setdefault(layout.pk, load_graph(map=layout))
        choice = _nearest_vehicle(order, idle, graph, layout)
        if choice is None:
            continue
        vehicle, route = choice
        if _assign(order=order, vehicle=vehicle, route=route):
            idle.remove(vehicle)
            assigned.append(order)
    return assigned


def _nearest_vehicle(
    order: TransportOrder, idle: list[Vehicle], graph: RoutingGraph, layout: Map
) -> tuple[Vehicle, list[str]] | None:
    pickup, drop = order.source.node.node_id, order.destination.node.node_id
    distance_to_pickup = graph.distances_to(pickup)
    reachable = [
        v for v in idle if v.map_id == layout.map_id and v.last_node_id in distance_to_pickup
    ]
    if not reachable:
        return None
    vehicle = min(reachable, key=lambda v: (distance_to_pickup[v.last_node_id], v.pk))
    route = (
        graph.shortest_path(vehicle.last_node_id, pickup) + graph.shortest_path(pickup, drop)[1:]
    )
    return vehicle, route


def _assign(*, order: TransportOrder, vehicle: Vehicle, route: list[str]) -> bool:
    now = timezone.now()
    try:
        with transaction.atomic():
            claimed = TransportOrder.objects.filter(
                pk=order.pk, status=Status.NEW, cancel_requested=False
            ).update(
                status=Status.ASSIGNED,
                vehicle=vehicle,
                route=route,
                assigned_at=now,
                vda_order_id=f"TO-{order.pk}",
                updated_at=now,
            )
            if not claimed:
                return False
            _record(order, OrderEvent.Kind.ASSIGNED, vehicle=str(vehicle), route=route)
    except IntegrityError:
        logger.info("vehicle %s was taken by a concurrent dispatch", vehicle)
        return False
    transaction.on_commit(lambda: send_command("order.assigned", order=order.pk))
    broadcast_on_commit(LIVE_GROUP, "orders.changed", {"order": order.pk})
    return True


@transaction.atomic
def mark_order_started(*, order_id: int) -> None:
    """The vehicle accepted the VDA 5050 order (control saw it in the vehicle's state)."""
    if _transition(order_id, {Status.ASSIGNED}, Status.IN_PROGRESS, started_at=timezone.now()):
        _record_id(order_id, OrderEvent.Kind.STARTED)


@transaction.atomic
def mark_step_reached(*, order_id: int, step: str, node_id: str) -> None:
    """The vehicle finished the pick or drop action of the order at `node_id`."""
    _record_id(order_id, OrderEvent.Kind.STEP_REACHED, step=step, node=node_id)


@transaction.atomic
def mark_order_finished(*, order_id: int) -> None:
    """The vehicle drove the whole route and finished its actions."""
    if _transition(
        order_id, set(TransportOrder.ACTIVE_STATUSES), Status.FINISHED, finished_at=timezone.now()
    ):
        _record_id(order_id, OrderEvent.Kind.FINISHED)
        _on_commit_dispatch()


@transaction.atomic
def mark_order_failed(*, order_id: int, reason: str) -> None:
    """The order cannot complete (rejected by the vehicle, failed action, fatal error)."""
    if _transition(
        order_id,
        set(TransportOrder.OPEN_STATUSES),
        Status.FAILED,
        finished_at=timezone.now(),
        failure_reason=reason[:2000],
    ):
        _record_id(order_id, OrderEvent.Kind.FAILED, reason=reason)
        _on_commit_dispatch()


@transaction.atomic
def requeue_order(*, order_id: int, reason: str) -> None:
    """Give an assigned order back to dispatch: the vehicle could not start it as planned
    (it is no longer where the route begins). Orders already started are never requeued."""
    if _transition(
        order_id, {Status.ASSIGNED}, Status.NEW, vehicle=None, route=[], assigned_at=None
    ):
        _record_id(order_id, OrderEvent.Kind.REQUEUED, reason=reason)
        _on_commit_dispatch()


@transaction.atomic
def mark_order_cancelled(*, order_id: int) -> None:
    """The vehicle stopped after a cancel request (control confirmed cancelOrder finished)."""
    if _transition(
        order_id, set(TransportOrder.OPEN_STATUSES), Status.CANCELLED, finished_at=timezone.now()
    ):
        _record_id(order_id, OrderEvent.Kind.CANCELLED)
        _on_commit_dispatch()


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
        _record(order, OrderEvent.Kind.CANCELLED, reason=reason, by=_who(by))
    elif not order.cancel_requested:
        order.cancel_requested = True
        order.save(update_fields=["cancel_requested", "updated_at"])
        _record(order, OrderEvent.Kind.CANCEL_REQUESTED, reason=reason, by=_who(by))
        transaction.on_commit(lambda: send_command("order.cancel", order=order.pk))
    broadcast_on_commit(LIVE_GROUP, "orders.changed", {"order": order.pk})
    return order


def _transition(order_id: int, allowed: set[str], target: str, **fields: Any) -> bool:
    updated = TransportOrder.objects.filter(pk=order_id, status__in=allowed).update(
        status=target, updated_at=timezone.now(), **fields
    )
    if updated:
        broadcast_on_commit(LIVE_GROUP, "orders.changed", {"order": order_id})
    return bool(updated)


def _record(order: TransportOrder, kind: str, **detail: Any) -> None:
    _record_id(order.pk, kind, **detail)


def _record_id(order_id: int, kind: str, **detail: Any) -> None:
    OrderEvent.objects.create(order_id=order_id, kind=kind, detail=detail)


def _who(user: AbstractBaseUser | AnonymousUser | None) -> str:
    return str(user) if user is not None and user.is_authenticated else "system"


def _on_commit_dispatch() -> None:
    from orders.tasks import dispatch_pending_orders_task

    transaction.on_commit(dispatch_pending_orders_task.delay)
