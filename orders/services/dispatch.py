"""Dispatch: assigning pending transport orders to idle vehicles in batches, and the reconciler
that gives back assignments control never sent."""

import logging
from collections import defaultdict
from collections.abc import Iterator
from contextlib import contextmanager
from datetime import datetime, timedelta

from django.db import IntegrityError, connection, transaction
from django.db.models import Q
from django.utils import timezone

from fleet.control_queue import send_command
from fleet.realtime import LIVE_GROUP, broadcast_on_commit
from maps.models import Map
from maps.selectors import load_graph
from orders import selectors
from orders.assignment import Candidate, Job, plan_batch
from orders.conf import setting
from orders.models import OrderEvent, TransportOrder
from orders.services.events import dispatch_on_commit, record, transition
from robots.models import Vehicle
from traffic import NoRouteError, RoutingGraph

logger = logging.getLogger(__name__)
Status = TransportOrder.Status
_LOCK_KEY = 5050_0005  # PostgreSQL advisory lock id of the dispatch cycle


def dispatch_pending_orders(*, now: datetime | None = None) -> list[TransportOrder]:
    """Run one dispatch cycle: assign waiting orders to idle vehicles, note why the rest wait.

    Per map, the most urgent orders (as many as there are idle vehicles) are matched to vehicles
    by `orders.assignment.plan_batch` on routing distance to the pickup. Orders before their
    earliest start wait. Safe to run concurrently: cycles take turns on a PostgreSQL advisory
    lock, an order is claimed with a conditional update, and the database's
    one-active-order-per-vehicle constraint refuses a vehicle that someone else took first.
    """
    now = now or timezone.now()
    with _cycle_lock():
        pending = list(selectors.list_pending_orders())
        if not pending:
            return []
        notes: dict[int, str] = {}
        ready = []
        for order in pending:
            if order.earliest_start and order.earliest_start > now:
                start = order.earliest_start.isoformat(timespec="seconds")
                notes[order.pk] = f"waits for its earliest start ({start})"
            else:
                ready.append(order)
        assigned = _assign_ready(ready, notes, now)
        _save_notes(pending, notes)
    return assigned


def _assign_ready(
    ready: list[TransportOrder], notes: dict[int, str], now: datetime
) -> list[TransportOrder]:
    if not ready:
        return []
    hold = timedelta(seconds=float(setting("COMMAND_HOLD")))
    fleet = selectors.get_dispatch_fleet(held_since=now - hold)
    if not fleet.idle:
        notes.update(dict.fromkeys((o.pk for o in ready), _fleet_note(fleet)))
        return []
    idle_since = selectors.get_idle_since(vehicle_ids=[v.pk for v in fleet.idle])
    by_map: dict[int, list[TransportOrder]] = defaultdict(list)
    layouts: dict[int, Map] = {}
    for order in ready:
        by_map[order.source.map_id].append(order)
        layouts[order.source.map_id] = order.source.map
    assigned: list[TransportOrder] = []
    for map_pk, orders in by_map.items():
        layout = layouts[map_pk]
        vehicles = [v for v in fleet.idle if v.map_id == layout.map_id]
        if not vehicles:
            notes.update(
                dict.fromkeys((o.pk for o in orders), f"no idle vehicle on map {layout.map_id}")
            )
            continue
        assigned += _assign_on_map(layout, orders, vehicles, idle_since, notes, now)
    return assigned


def _assign_on_map(
    layout: Map,
    orders: list[TransportOrder],
    vehicles: list[Vehicle],
    idle_since: dict[int, datetime],
    notes: dict[int, str],
    now: datetime,
) -> list[TransportOrder]:
    graph = load_graph(map=layout)
    jobs = [
        Job(
            key=o.pk,
            pickup=o.source.node.node_id,
            station=o.source.station_id,
            priority=o.priority,
            deadline=o.deadline,
            created=o.created_at,
        )
        for o in orders
    ]
    candidates = [Candidate(v.pk, v.last_node_id, idle_since.get(v.pk)) for v in vehicles]
    plan = plan_batch(jobs, candidates, graph.distances_to, now=now)
    notes.update(plan.notes)
    order_by_pk = {o.pk: o for o in orders}
    vehicle_by_pk = {v.pk: v for v in vehicles}
    assigned = []
    for job, candidate, _ in plan.pairs:
        order, vehicle = order_by_pk[job.key], vehicle_by_pk[candidate.key]
        route = _route(graph, vehicle, order)
        if route is None:
            notes[order.pk] = f"{order.destination.station_id} cannot be reached from the source"
        elif _assign(order=order, vehicle=vehicle, route=route):
            assigned.append(order)
        else:
            notes[order.pk] = "the chosen vehicle was taken meanwhile; next cycle"
    return assigned


def _route(graph: RoutingGraph, vehicle: Vehicle, order: TransportOrder) -> list[str] | None:
    pickup, drop = order.source.node.node_id, order.destination.node.node_id
    try:
        return (
            graph.shortest_path(vehicle.last_node_id, pickup)
            + graph.shortest_path(pickup, drop)[1:]
        )
    except NoRouteError:
        return None


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
                sent_at=None,
                vda_order_id=f"TO-{order.pk}",
                dispatch_note="",
                updated_at=now,
            )
            if not claimed:
                return False
            record(order.pk, OrderEvent.Kind.ASSIGNED, vehicle=str(vehicle), route=route)
            order_id = order.pk
            transaction.on_commit(
                lambda: send_command("order.assigned", order=order_id), robust=True
            )
            broadcast_on_commit(LIVE_GROUP, "orders.changed", {"order": order.pk})
    except IntegrityError:
        logger.info("vehicle %s was taken by a concurrent dispatch", vehicle)
        return False
    order.status, order.vehicle, order.route = Status.ASSIGNED, vehicle, route
    return True


def _fleet_note(fleet: selectors.DispatchFleet) -> str:
    if not fleet.online:
        return "no vehicle online"
    reasons = [f"{fleet.busy} busy"] if fleet.busy else []
    reasons += [f"{count} {reason}" for reason, count in sorted(fleet.unavailable.items())]
    return "no vehicle available: " + ", ".join(reasons)


def _save_notes(pending: list[TransportOrder], notes: dict[int, str]) -> None:
    """Write the notes that changed, one UPDATE per distinct note (not a row per order)."""
    changed: dict[str, list[int]] = defaultdict(list)
    for order in pending:
        note = notes.get(order.pk)
        if note is not None and note[:200] != order.dispatch_note:
            changed[note[:200]].append(order.pk)
    for note, pks in changed.items():
        TransportOrder.objects.filter(pk__in=pks, status=Status.NEW).update(dispatch_note=note)


@contextmanager
def _cycle_lock() -> Iterator[None]:
    """One dispatch cycle at a time on PostgreSQL (concurrent cycles would only contend for the
    same vehicles); SQLite serializes writers anyway."""
    if connection.vendor != "postgresql":
        yield
        return
    with connection.cursor() as cursor:
        cursor.execute("SELECT pg_advisory_lock(%s)", [_LOCK_KEY])
    try:
        yield
    finally:
        with connection.cursor() as cursor:
            cursor.execute("SELECT pg_advisory_unlock(%s)", [_LOCK_KEY])


def reconcile_stale_assignments(*, now: datetime | None = None) -> list[int]:
    """Give back to dispatch the orders assigned longer than the lease (FLEET_ORDERS
    ASSIGNMENT_LEASE) that control evidently never sent: see
    `selectors.list_stale_assignments` for how conservative that is. Returns their ids."""
    now = now or timezone.now()
    lease = float(setting("ASSIGNMENT_LEASE"))
    requeued = []
    for order in selectors.list_stale_assignments(assigned_before=now - timedelta(seconds=lease)):
        if _release(order, f"not started within {lease:.0f} s; {order.vehicle} never received it"):
            requeued.append(order.pk)
    return requeued


@transaction.atomic
def _release(order: TransportOrder, reason: str) -> bool:
    unchanged = Q(
        vehicle_id=order.vehicle_id,
        assigned_at=order.assigned_at,
        sent_at__isnull=True,
        started_at__isnull=True,
        cancel_requested=False,
    )
    released = transition(
        order.pk,
        {Status.ASSIGNED},
        Status.NEW,
        where=unchanged,
        vehicle=None,
        route=[],
        assigned_at=None,
        dispatch_note="requeued: " + reason[:180],
    )
    if released:
        record(order.pk, OrderEvent.Kind.REQUEUED, reason=reason, by="reconciler")
        dispatch_on_commit()
    return released
