"""Charging jobs: who charges, at which point, when to stop; and their progress from `control`.

`plan_charging` runs every few seconds (Celery beat): it closes sessions whose vehicle left
the charger, stops charging where the policy says so (`stopCharging` through `control`), opens
sessions for idle vehicles that need (or may opportunistically take) a charge, and gives free
charging points to the queue (`battery.planning.assign_points`). An assigned session carries
the route to its point; `control` drives it as a VDA 5050 order that ends in `startCharging`
and reports progress back through `apply_charge_progress`.
"""

import logging
from collections import defaultdict
from collections.abc import Callable
from dataclasses import dataclass, field
from datetime import datetime

from django.db import IntegrityError, transaction
from django.utils import timezone

from battery.models import Charger, ChargeSession, VehicleEnergy
from battery.planning import ChargePoint, ChargeRequest, assign_points
from battery.policy import Reason
from battery.selectors import (
    PolicyBook,
    busy_vehicle_ids,
    get_policy_book,
    list_open_sessions,
    vehicle_type_id,
)
from fleet.control_queue import send_command
from fleet.exceptions import DomainError, InvalidRequestError
from maps.models import Map, Station, VehicleType
from maps.selectors import load_graph
from robots.models import Vehicle
from traffic import NoRouteError, RoutingGraph

logger = logging.getLogger(__name__)
Status = ChargeSession.Status


@dataclass
class ChargingCycle:
    """What one planning cycle did, for logs and tests."""

    opened: list[int] = field(default_factory=list)
    assigned: list[int] = field(default_factory=list)
    stopped: list[int] = field(default_factory=list)
    closed: list[int] = field(default_factory=list)
    queue: dict[int, int] = field(default_factory=dict)


def point_node(charger: Charger, point: int) -> str:
    """The node of charging point `point`: the station's interaction node of that rank, else its
    primary node (several plugs at one bay)."""
    nodes = [sn.node.node_id for sn in charger.station.station_nodes.select_related("node")]
    return nodes[point] if point < len(nodes) else charger.station.node.node_id


def plan_charging(
    *, work_waiting: bool | None = None, now: datetime | None = None
) -> ChargingCycle:
    """One charging cycle (see the module docstring). `work_waiting` defaults to whether any
    transport order waits for a vehicle."""
    now = now or timezone.now()
    cycle = ChargingCycle()
    if work_waiting is None:
        work_waiting = _work_waiting()
    book = get_policy_book()
    sessions = list(list_open_sessions())
    busy = busy_vehicle_ids()
    queue_waiting = any(s.status == Status.QUEUED for s in sessions)
    for session in sessions:
        _follow(session, book, busy, work_waiting, queue_waiting, now, cycle)
    _open_requests(book, busy, work_waiting, {s.vehicle_id for s in sessions}, cycle)
    _assign(book, cycle)
    return cycle


def _work_waiting() -> bool:
    from django.apps import apps

    # Read by name: transport orders are a layer above this app.
    order_model = apps.get_model("orders", "TransportOrder")
    return bool(order_model.objects.filter(status="NEW", cancel_requested=False).exists())


def _follow(
    session: ChargeSession,
    book: PolicyBook,
    busy: set[int],
    work_waiting: bool,
    queue_waiting: bool,
    now: datetime,
    cycle: ChargingCycle,
) -> None:
    vehicle = session.vehicle
    charge = vehicle.battery_charge
    if session.status == Status.QUEUED and vehicle.pk in busy:
        # An opportunity request that dispatch overtook with work: no longer wanted.
        _close(session, Status.CANCELLED, charge, now, "took a transport order")
        cycle.closed.append(session.pk)
        return
    if session.status in {Status.CHARGING, Status.STOPPING} and session.charger is not None:
        on_point = vehicle.last_node_id == point_node(session.charger, session.point or 0)
        if not on_point and not vehicle.charging:
            _close(session, Status.DONE, charge, now, "left the charger")
            cycle.closed.append(session.pk)
            return
    if session.status == Status.CHARGING and charge is not None:
        levels = book.for_vehicle(vehicle)
        if levels.stop_charging(charge, work_waiting=work_waiting, queue_waiting=queue_waiting):
            ChargeSession.objects.filter(pk=session.pk, status=Status.CHARGING).update(
                status=Status.STOPPING, end_charge=charge
            )
            send_command(
                "vehicle.instant_action",
                vehicle=vehicle.pk,
                action_type="stopCharging",
                parameters={},
            )
            cycle.stopped.append(session.pk)


def _close(
    session: ChargeSession, status: str, charge: float | None, now: datetime, note: str
) -> None:
    ChargeSession.objects.filter(pk=session.pk).update(
        status=status, ended_at=now, end_charge=charge, note=note[:200]
    )


def _open_requests(
    book: PolicyBook, busy: set[int], work_waiting: bool, open_ids: set[int], cycle: ChargingCycle
) -> None:
    if not Charger.objects.filter(is_active=True).exists():
        return
    vehicles = Vehicle.objects.filter(connection=Vehicle.Connection.ONLINE).exclude(
        pk__in=open_ids | busy
    )
    energy = dict(VehicleEnergy.objects.values_list("vehicle_id", "drain_per_hour"))
    for vehicle in vehicles:
        if vehicle.battery_charge is None or not vehicle.is_available:
            continue
        levels = book.for_vehicle(vehicle)
        reason = levels.charge_reason(
            vehicle.battery_charge,
            idle=True,
            work_waiting=work_waiting,
            drain_per_hour=energy.get(vehicle.pk),
        )
        if reason is None:
            continue
        try:
            with transaction.atomic():
                session = ChargeSession.objects.create(
                    vehicle=vehicle, reason=str(reason), start_charge=vehicle.battery_charge
                )
        except IntegrityError:
            continue  # opened meanwhile
        cycle.opened.append(session.pk)


def _assign(book: PolicyBook, cycle: ChargingCycle) -> None:
    """Give free points to queued sessions, per map; the booking constraint settles races."""
    queued = list(ChargeSession.objects.filter(status=Status.QUEUED).select_related("vehicle"))
    if not queued:
        return
    booked = set(
        ChargeSession.objects.filter(
            status__in=["ASSIGNED", "DRIVING", "CHARGING", "STOPPING"], charger__isnull=False
        ).values_list("charger_id", "point")
    )
    chargers = list(
        Charger.objects.filter(is_active=True)
        .select_related("station__node", "station__map")
        .prefetch_related("vehicle_types")
    )
    types = book.types or list(VehicleType.objects.all())
    stations = {c.pk: c.station.station_id for c in chargers}
    by_map: dict[str, list[ChargeSession]] = defaultdict(list)
    for session in queued:
        by_map[session.vehicle.map_id].append(session)
    for map_id, sessions in by_map.items():
        layout = Map.objects.filter(map_id=map_id).first()
        if layout is None:
            continue
        graph = load_graph(map=layout)
        free = [
            ChargePoint(
                charger.pk,
                point,
                point_node(charger, point),
                frozenset(t.type_id for t in charger.vehicle_types.all()) or None,
            )
            for charger in chargers
            if charger.station.map_id == layout.pk
            for point in range(charger.capacity)
            if (charger.pk, point) not in booked
        ]
        by_pk = {s.pk: s for s in sessions}
        groups: dict[str, list[ChargeRequest]] = defaultdict(list)
        for session in sessions:
            groups[session.wanted_station].append(
                ChargeRequest(
                    key=session.pk,
                    node=session.vehicle.last_node_id,
                    charge=session.vehicle.battery_charge or 0.0,
                    reason=Reason(session.reason),
                    vehicle_type=vehicle_type_id(session.vehicle, types),
                    since=session.created_at.timestamp(),
                )
            )
        # Staff's choices first, each on its station's points; then everyone on the rest.
        for wanted in sorted(groups, key=lambda station: station == ""):
            points = [p for p in free if not wanted or stations[p.charger] == wanted]
            plan = assign_points(groups[wanted], points, _distances(graph))
            cycle.queue.update(plan.queue)
            for request, point, _ in plan.assigned:
                free.remove(point)
                if _book(by_pk[request.key], point, graph):
                    cycle.assigned.append(request.key)


def _distances(graph: RoutingGraph) -> Callable[[str], dict[str, float]]:
    def distances_to(node: str) -> dict[str, float]:
        try:
            return graph.distances_to(node)
        except NoRouteError:
            return {}

    return distances_to


def _book(session: ChargeSession, point: ChargePoint, graph: RoutingGraph) -> bool:
    try:
        route = graph.shortest_path(session.vehicle.last_node_id, point.node)
    except NoRouteError:
        return False
    try:
        with transaction.atomic():
            claimed = ChargeSession.objects.filter(pk=session.pk, status=Status.QUEUED).update(
                status=Status.ASSIGNED,
                charger_id=point.charger,
                point=point.point,
                route=route,
                vda_order_id=f"CS-{session.pk}",
            )
    except IntegrityError:
        logger.info("charging point %s/%s was taken meanwhile", point.charger, point.point)
        return False
    if claimed:
        pk = session.pk
        transaction.on_commit(lambda: send_command("order.assigned", charge_session=pk))
    return bool(claimed)


def request_charge(
    *, vehicle_id: int, station_id: str = "", command_id: int | None = None
) -> ChargeSession:
    """Staff sent the vehicle to charge (at `station_id`, else the nearest free point)."""
    vehicle = Vehicle.objects.filter(pk=vehicle_id).first()
    if vehicle is None:
        raise InvalidRequestError(f"no vehicle {vehicle_id}")
    if (
        station_id
        and not Charger.objects.filter(
            station__station_id=station_id, station__map__map_id=vehicle.map_id, is_active=True
        ).exists()
    ):
        raise InvalidRequestError(f"{station_id} is no active charger on {vehicle.map_id}")
    if not station_id and not Charger.objects.filter(is_active=True).exists():
        station = Station.objects.filter(map__map_id=vehicle.map_id, kind=Station.Kind.CHARGE)
        raise InvalidRequestError(
            "no charger is configured"
            + (f" (charge stations: {station.count()})" if station else "")
        )
    try:
        with transaction.atomic():
            return ChargeSession.objects.create(
                vehicle=vehicle,
                reason=ChargeSession.Reason.MANUAL,
                wanted_station=station_id,
                command_id=command_id,
                start_charge=vehicle.battery_charge,
            )
    except IntegrityError:
        raise DomainError(f"{vehicle} already has a charge session") from None


_PROGRESS = {
    "sent": ({Status.ASSIGNED}, Status.DRIVING),
    "started": ({Status.ASSIGNED, Status.DRIVING}, Status.DRIVING),
    "step": ({Status.ASSIGNED, Status.DRIVING}, Status.CHARGING),
    "finished": ({Status.ASSIGNED, Status.DRIVING}, Status.CHARGING),
    "failed": ({Status.ASSIGNED, Status.DRIVING}, Status.FAILED),
    "cancelled": ({Status.ASSIGNED, Status.DRIVING}, Status.CANCELLED),
    "requeued": ({Status.ASSIGNED, Status.DRIVING}, Status.QUEUED),
}


def apply_charge_progress(*, session_id: int, kind: str, reason: str = "") -> bool:
    """What `control` saw of a charge job: sent, started, charging started (the startCharging
    step or the order finished), failed, cancelled or requeued (route no longer valid)."""
    rule = _PROGRESS.get(kind)
    if rule is None:
        return False
    allowed, target = rule
    now = timezone.now()
    fields: dict[str, object] = {"status": target}
    if target == Status.CHARGING:
        fields["started_at"] = now
    elif target in {Status.FAILED, Status.CANCELLED}:
        fields |= {"ended_at": now, "note": reason[:200]}
    elif target == Status.QUEUED:
        fields |= {"charger": None, "point": None, "route": [], "note": reason[:200]}
    return bool(ChargeSession.objects.filter(pk=session_id, status__in=allowed).update(**fields))


def cancel_session(*, session: ChargeSession, note: str = "cancelled by staff") -> None:
    """Cancel a queued session (one that is driving or charging ends through the vehicle)."""
    if session.status != Status.QUEUED:
        raise DomainError(f"session {session.pk} is {session.status}; only queued ones cancel")
    _close(session, Status.CANCELLED, session.vehicle.battery_charge, timezone.now(), note)


def create_missing_chargers() -> list[str]:
    """A charger with one point for every charge station without one; their station ids."""
    stations = Station.objects.filter(kind=Station.Kind.CHARGE, charger__isnull=True)
    created = [Charger(station=station) for station in stations]
    Charger.objects.bulk_create(created)
    return [c.station.station_id for c in created]
