"""Dispatch: assigning pending transport orders to idle vehicles in batches, and the reconciler
that gives back assignments control never sent."""

import logging
from collections import defaultdict
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass, field
from datetime import datetime, timedelta

from django.db import IntegrityError, connection, transaction
from django.db.models import Q
from django.utils import timezone

from battery import selectors as battery_selectors
from fleet.control_queue import send_command
from fleet.realtime import LIVE_GROUP, broadcast_on_commit
from inventory import selectors as inventory_selectors
from maintenance import selectors as maintenance_selectors
from maps.models import Map, VehicleType
from maps.selectors import load_graph, vehicle_profile
from orders import capability, selectors
from orders.assignment import Candidate, Job, Plan, plan_batch
from orders.conf import setting
from orders.models import OrderEvent, OrderSequence, TransportOrder
from orders.services import dispatch_shortlist
from orders.services.dispatch_factsheets import Digest, attach_factsheets
from orders.services.events import dispatch_on_commit, record, transition
from orders.services.fit import Capabilities, allowed_vehicles, order_steps, route_through_steps
from orders.services.vehicle_events import emit_vehicle_order_event
from orders.services.webhooks import subscriptions_read_once
from robots.models import Vehicle
from traffic import NoRouteError, RoutingGraph, VehicleProfile

logger = logging.getLogger(__name__)
Status = TransportOrder.Status
_LOCK_KEY = 5050_0005  # PostgreSQL advisory lock id of the dispatch cycle


def dispatch_pending_orders(*, now: datetime | None = None) -> list[TransportOrder]:
    """Run one dispatch cycle: assign waiting orders to idle vehicles, note why the rest wait.

    Per map, the most urgent orders (as many as there are idle vehicles) are matched to vehicles
    by `orders.assignment.plan_batch` on travel time to the first step, priced per vehicle type
    (speeds, type restrictions) from the routing graph's cached tables. An order takes only its
    intended vehicle, vehicles of its vehicle type, and vehicles whose factsheet allows its load
    type and step actions; the note says which of these keeps it waiting. Orders before their
    earliest start wait. A few orders among many idle vehicles are matched against the nearest
    of them only, when that gives the whole fleet's plan (`dispatch_shortlist`; issue 11: a
    new order in a 1,000-vehicle fleet is assigned in tens of milliseconds, not a quarter of a
    second). Safe to run concurrently: cycles take turns on a PostgreSQL advisory
    lock, an order is claimed with a conditional update, and the database's
    one-active-order-per-vehicle constraint refuses a vehicle that someone else took first.
    Once the assignments commit, one `order.assigned` command wakes control to send them.
    """
    now = now or timezone.now()
    with _cycle_lock():
        pending = list(selectors.list_pending_orders())
        if not pending:
            return []
        notes: dict[int, str] = {}
        ready = []
        gate = selectors.get_sequence_gate(orders=pending)
        for order in pending:
            if order.earliest_start and order.earliest_start > now:
                start = order.earliest_start.isoformat(timespec="seconds")
                notes[order.pk] = f"waits for its earliest start ({start})"
            elif order.pk in gate.waiting:
                notes[order.pk] = gate.waiting[order.pk]
            else:
                ready.append(order)
        with subscriptions_read_once():
            assigned = _assign_ready(ready, notes, _Cycle(now, gate))
        if assigned:  # wakes control to read them at once: one command a cycle, not an order
            ids = [o.pk for o in assigned]
            transaction.on_commit(lambda: send_command("order.assigned", orders=ids), robust=True)
        _save_notes(pending, notes)
    return assigned


@dataclass
class _Cycle:
    """What a dispatch cycle reads once and its steps share (each read cost every cycle a
    round trip to the database; docs/LOAD.md, twelfth round)."""

    now: datetime
    gate: selectors.SequenceGate
    types: list[VehicleType] = field(default_factory=list)  # the layouts' vehicle types
    short: dispatch_shortlist.Shortlist | None = None  # the shortlist being tried
    energy: battery_selectors.DispatchEnergy | None = None  # of the idle vehicles


def _assign_ready(
    ready: list[TransportOrder], notes: dict[int, str], cycle: _Cycle
) -> list[TransportOrder]:
    if not ready:
        return []
    held_since = cycle.now - timedelta(seconds=float(setting("COMMAND_HOLD")))
    cycle.types = list(VehicleType.objects.all())
    # A few orders and many idle vehicles: the nearest few decide (dispatch_shortlist).
    cycle.short = dispatch_shortlist.shortlist(
        orders=ready, held_since=held_since, gate=cycle.gate, types=cycle.types
    )
    if cycle.short is not None:
        fleet = selectors.DispatchFleet(idle=cycle.short.idle)
        _available(fleet, cycle, cycle.short.digests)
        plans = _plan_maps(ready, fleet.idle, {}, cycle) if fleet.idle else None
        if plans is not None:
            return _carry_out(plans, notes)
        cycle.short = None
    fleet = selectors.get_dispatch_fleet(held_since=held_since, with_factsheets=False)
    _available(fleet, cycle)
    if not fleet.idle:
        notes.update(dict.fromkeys((o.pk for o in ready), _fleet_note(fleet)))
        return []
    plans = _plan_maps(ready, fleet.idle, notes, cycle)
    return _carry_out(plans or [], notes)


def _available(
    fleet: selectors.DispatchFleet, cycle: _Cycle, digests: dict[int, Digest] | None = None
) -> None:
    """Attach the idle vehicles' factsheets and drop those held back (battery, maintenance)
    from `fleet`; the battery facts read for them go to `cycle` (its job refusals use them)."""
    attach_factsheets(fleet.idle, digests)  # decoded once per change, not every cycle
    cycle.energy = _hold_back(fleet)


@dataclass
class _MapPlan:
    """The plan of one map, ready to carry out: pairs, and what they need to be routed."""

    graph: RoutingGraph
    plan: Plan
    orders: dict[int, TransportOrder]
    vehicles: dict[int, Vehicle]
    profiles: dict[int, VehicleProfile]
    energy: battery_selectors.DispatchEnergy | None = None


def _plan_maps(
    ready: list[TransportOrder], idle: list[Vehicle], notes: dict[int, str], cycle: _Cycle
) -> list[_MapPlan] | None:
    """Plan every map's orders against its idle vehicles (nothing written yet). With a
    shortlist, None unless its plans are the whole fleet's (then the caller plans again)."""
    idle_since = selectors.get_idle_since(vehicle_ids=[v.pk for v in idle])
    by_map: dict[int, list[TransportOrder]] = defaultdict(list)
    layouts: dict[int, Map] = {}
    for order in ready:
        by_map[order.source.map_id].append(order)
        layouts[order.source.map_id] = order.source.map
    plans = []
    for map_pk, orders in by_map.items():
        layout = layouts[map_pk]
        vehicles = [v for v in idle if v.map_id == layout.map_id]
        if not vehicles:
            if cycle.short is not None:
                return None
            notes.update(
                dict.fromkeys((o.pk for o in orders), f"no idle vehicle on map {layout.map_id}")
            )
            continue
        planned = _plan_on_map(layout, orders, vehicles, idle_since, notes, cycle)
        if planned is None:
            return None
        plans.append(planned)
    return plans


def _plan_on_map(
    layout: Map,
    orders: list[TransportOrder],
    vehicles: list[Vehicle],
    idle_since: dict[int, datetime],
    notes: dict[int, str],
    cycle: _Cycle,
) -> _MapPlan | None:
    short, gate = cycle.short, cycle.gate
    graph = (short.graphs.get(layout.pk) if short else None) or load_graph(map=layout)
    types = selectors.get_vehicle_types(vehicles=vehicles, types=cycle.types)
    factsheets = {v.pk: v.factsheet for v in vehicles}
    profiles = {
        pk: capability.with_height(vehicle_profile(vehicle_type=t), factsheets[pk])
        for pk, t in types.items()
    }
    capabilities = Capabilities(
        vehicles, inventory_selectors.load_weights(o.load_id for o in orders)
    )
    jobs = []
    for order in orders:
        allowed, note = allowed_vehicles(order, vehicles, types, gate, capabilities)
        if note is not None:
            notes[order.pk] = note
            continue
        steps = order_steps(order)
        jobs.append(
            Job(
                key=order.pk,
                pickup=steps[0].station.node.node_id,
                station=steps[0].station.station_id,
                priority=order.priority,
                deadline=order.deadline,
                created=order.created_at,
                allowed=allowed,
            )
        )
    candidates = [
        Candidate(v.pk, v.last_node_id, idle_since.get(v.pk), profiles.get(v.pk)) for v in vehicles
    ]
    if short is not None and not short.covers(orders, jobs, candidates, graph.travel_times_to):
        return None
    plan = plan_batch(
        jobs,
        candidates,
        graph.travel_times_to,
        now=cycle.now,
        by_profile=lambda goal, profile: _travel_times(graph, goal, profile),  # type: ignore[arg-type]
    )
    if short is not None and (plan.notes or len(plan.pairs) != len(orders)):
        return None  # an order the shortlist does not serve may still have a vehicle
    notes.update(plan.notes)
    order_by_pk = {o.pk: o for o in orders}
    vehicle_by_pk = {v.pk: v for v in vehicles}
    return _MapPlan(graph, plan, order_by_pk, vehicle_by_pk, profiles, cycle.energy)


def _carry_out(plans: list[_MapPlan], notes: dict[int, str]) -> list[TransportOrder]:
    """Route and assign the planned pairs (each claimed on its own, see `_assign`)."""
    assigned = []
    for map_plan in plans:
        for job, candidate, _ in map_plan.plan.pairs:
            order = map_plan.orders[job.key]
            vehicle = map_plan.vehicles[candidate.key]
            if _route_and_assign(map_plan, order, vehicle, notes):
                assigned.append(order)
    return assigned


def _route_and_assign(
    map_plan: _MapPlan, order: TransportOrder, vehicle: Vehicle, notes: dict[int, str]
) -> bool:
    profile = map_plan.profiles.get(vehicle.pk)
    loaded = capability.loaded(profile, vehicle.factsheet, order.load_type)
    planned = route_through_steps(map_plan.graph, vehicle, order_steps(order), profile, loaded)
    if isinstance(planned, str):
        notes[order.pk] = planned
    elif refusal := battery_selectors.job_refusal(
        vehicle=vehicle, route=planned[0], graph=map_plan.graph, energy=map_plan.energy
    ):
        notes[order.pk] = f"{vehicle}: {refusal}"
    elif _assign(order=order, vehicle=vehicle, route=planned[0], route_steps=planned[1]):
        return True
    else:
        notes[order.pk] = "the chosen vehicle was taken meanwhile; next cycle"
    return False


def _travel_times(graph: RoutingGraph, goal: str, profile: VehicleProfile) -> dict[str, float]:
    """Seconds to `goal` for vehicles of `profile`; none when their type may not use the goal
    (LIF: the node has no property for that type), instead of failing the whole cycle."""
    try:
        return graph.travel_times_to(goal, vehicle=profile)
    except NoRouteError:
        return {}


def _assign(
    *, order: TransportOrder, vehicle: Vehicle, route: list[str], route_steps: list[int]
) -> bool:
    now = timezone.now()
    try:
        with transaction.atomic():
            claimed = TransportOrder.objects.filter(
                pk=order.pk, status=Status.NEW, cancel_requested=False
            ).update(
                status=Status.ASSIGNED,
                vehicle=vehicle,
                route=route,
                route_steps=route_steps,
                assigned_at=now,
                sent_at=None,
                vda_order_id=f"TO-{order.pk}",
                dispatch_note="",
                updated_at=now,
            )
            if not claimed:
                return False
            if order.sequence_id is not None:  # the sequence's first assignment binds it
                OrderSequence.objects.filter(pk=order.sequence_id, vehicle__isnull=True).update(
                    vehicle=vehicle
                )
            record(order.pk, OrderEvent.Kind.ASSIGNED, vehicle=str(vehicle), route=route)
            emit_vehicle_order_event(
                event_type="vehicle.order_assigned", vehicle=vehicle, order_id=order.pk
            )
            broadcast_on_commit(LIVE_GROUP, "orders.changed", {"order": order.pk})
    except IntegrityError:
        logger.info("vehicle %s was taken by a concurrent dispatch", vehicle)
        return False
    order.status, order.vehicle, order.route = Status.ASSIGNED, vehicle, route
    order.route_steps = route_steps
    return True


def _hold_back(fleet: selectors.DispatchFleet) -> battery_selectors.DispatchEnergy:
    """Move idle vehicles that charge, need charge, are below the critical charge level their
    factsheet states (3.0, REFERENCE J.46) or are out of service to `unavailable`; returns the
    battery facts read for them."""
    energy = battery_selectors.read_dispatch_energy(vehicles=fleet.idle)
    holds = battery_selectors.dispatch_holds(vehicles=fleet.idle, energy=energy)
    holds |= maintenance_selectors.out_of_service(vehicle_ids=[v.pk for v in fleet.idle])
    for vehicle in fleet.idle:  # below its factsheet's critical level: charging orders only
        critical = capability.critical_charge(vehicle.factsheet)
        charge = vehicle.battery_charge
        if critical is not None and charge is not None and charge < critical:
            holds.setdefault(vehicle.pk, "below its critical charge level")
    for reason in holds.values():
        fleet.unavailable[reason.split(" (")[0].split(":")[0]] += 1
    fleet.idle = [v for v in fleet.idle if v.pk not in holds]
    return energy


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
        if release_assignment(
            order, f"not started within {lease:.0f} s; {order.vehicle} never received it"
        ):
            requeued.append(order.pk)
    return requeued


@transaction.atomic
def release_assignment(order: TransportOrder, reason: str) -> bool:
    """Give an assigned order its vehicle never received back to dispatch, with the reason;
    False when it changed meanwhile (sent, started, cancelled or assigned anew)."""
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
        route_steps=[],
        assigned_at=None,
        vehicle_lost_at=None,
        dispatch_note="requeued: " + reason[:180],
    )
    if released:
        record(order.pk, OrderEvent.Kind.REQUEUED, reason=reason, by="reconciler")
        dispatch_on_commit()
    return released
