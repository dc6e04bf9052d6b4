"""Reads of the battery app: policies per vehicle, what holds vehicles back from work, the
projected charge after a job, charger occupancy and battery history."""

import math
from collections.abc import Iterable
from dataclasses import dataclass, field
from typing import Any

from django.db.models import QuerySet

from battery.models import (
    BOOKED_STATUSES,
    OPEN_SESSION_STATUSES,
    BatteryAlert,
    BatterySample,
    Charger,
    ChargeSession,
    ChargingPolicy,
    VehicleEnergy,
)
from battery.policy import Consumption, Levels
from maps.models import VehicleType
from robots.models import Vehicle
from traffic import NoRouteError, RoutingGraph

# Transport orders live above this app (orders depends on battery); their relation to the
# vehicle is read by name here, without importing the orders app.
BUSY_LOOKUP = {"transport_orders__status__in": ["ASSIGNED", "IN_PROGRESS"]}
Status = ChargeSession.Status


def levels_from(policy: ChargingPolicy | None) -> Levels:
    if policy is None:
        return Levels()
    return Levels(
        critical=policy.critical,
        needs_charge=policy.needs_charge,
        sufficient=policy.sufficient,
        charge_until=policy.charge_until,
        full=policy.full,
        opportunity_charging=policy.opportunity_charging,
        opportunity_below=policy.opportunity_below,
        shift_reserve_hours=policy.shift_reserve_hours,
    )


def vehicle_type_id(vehicle: Vehicle, types: Iterable[VehicleType]) -> str | None:
    """The LIF vehicle type of a vehicle: the type whose series (and manufacturer, if set) match
    its factsheet, or whose id is "manufacturer.series"."""
    series = str(((vehicle.factsheet or {}).get("typeSpecification") or {}).get("seriesName") or "")
    if not series:
        return None
    for vehicle_type in types:
        if vehicle_type.type_id == f"{vehicle.manufacturer}.{series}":
            return vehicle_type.type_id
        if vehicle_type.series_name == series and vehicle_type.manufacturer in (
            "",
            vehicle.manufacturer,
        ):
            return vehicle_type.type_id
    return None


@dataclass
class PolicyBook:
    """Every policy, resolved per vehicle by its type (the default for the rest)."""

    by_type: dict[str, Levels]
    default: Levels
    types: list[VehicleType]

    def for_vehicle(self, vehicle: Vehicle) -> Levels:
        type_id = vehicle_type_id(vehicle, self.types) if self.by_type else None
        return self.by_type.get(type_id or "", self.default)


def get_policy_book() -> PolicyBook:
    policies = list(ChargingPolicy.objects.select_related("vehicle_type"))
    default = next((p for p in policies if p.vehicle_type is None), None)
    by_type = {p.vehicle_type.type_id: levels_from(p) for p in policies if p.vehicle_type}
    types = list(VehicleType.objects.all()) if by_type else []
    return PolicyBook(by_type, levels_from(default), types)


def consumption_of(energy: VehicleEnergy | None) -> Consumption:
    if energy is None:
        return Consumption()
    return Consumption(per_metre=energy.drain_per_metre, per_hour=energy.drain_per_hour)


@dataclass
class DispatchEnergy:
    """The battery facts of a dispatch cycle's vehicles, read once for the cycle: the policies,
    each vehicle's learned consumption and open charge session, and the charger nodes of each
    map (read on first use). Holds and job refusals both need them; reading them per order cost
    a dispatch cycle four queries (docs/LOAD.md, twelfth round)."""

    book: PolicyBook
    energy: dict[int, VehicleEnergy]
    sessions: dict[int, ChargeSession]
    chargers: dict[str, list[str]] = field(default_factory=dict)  # map id -> charger nodes

    def charger_nodes(self, map_id: str) -> list[str]:
        if map_id not in self.chargers:
            self.chargers[map_id] = list(
                Charger.objects.filter(is_active=True, station__map__map_id=map_id).values_list(
                    "station__node__node_id", flat=True
                )
            )
        return self.chargers[map_id]


def read_dispatch_energy(*, vehicles: Iterable[Vehicle]) -> DispatchEnergy:
    """The battery facts of `vehicles` for one dispatch cycle (three queries)."""
    ids = [v.pk for v in vehicles]
    sessions = {
        s.vehicle_id: s
        for s in ChargeSession.objects.filter(vehicle_id__in=ids, status__in=OPEN_SESSION_STATUSES)
    }
    energy = {e.vehicle_id: e for e in VehicleEnergy.objects.filter(vehicle_id__in=ids)}
    return DispatchEnergy(get_policy_book(), energy, sessions)


def dispatch_holds(
    *, vehicles: Iterable[Vehicle], energy: DispatchEnergy | None = None
) -> dict[int, str]:
    """Vehicles that must not get work now, with the reason: charging or driving to a charger,
    queued for a charger because the battery is low, or below the working minimum. `energy`:
    the facts read for these vehicles (read here when not given)."""
    vehicles = list(vehicles)
    facts = energy if energy is not None else read_dispatch_energy(vehicles=vehicles)
    holds: dict[int, str] = {}
    for vehicle in vehicles:
        session = facts.sessions.get(vehicle.pk)
        if session is not None and session.status in {Status.ASSIGNED, Status.DRIVING}:
            holds[vehicle.pk] = "driving to a charger"
            continue
        if session is not None and session.status == Status.CHARGING:
            holds[vehicle.pk] = "charging"
            continue
        learned = facts.energy.get(vehicle.pk)
        per_hour = learned.drain_per_hour if learned else None
        levels = facts.book.for_vehicle(vehicle)
        if levels.job_refusal(vehicle.battery_charge, 0.0, per_hour) is not None:
            holds[vehicle.pk] = "battery low"
        elif (
            session is not None
            and session.status == Status.QUEUED
            and session.reason != ChargeSession.Reason.OPPORTUNITY  # yields to work
        ):
            holds[vehicle.pk] = "queued for a charger"
    return holds


def job_refusal(
    *,
    vehicle: Vehicle,
    route: list[str],
    graph: RoutingGraph,
    actions: int = 2,
    energy: DispatchEnergy | None = None,
) -> str | None:
    """Why `vehicle` must not drive `route` with `actions` load actions, or None when it may:
    its charge after the route and the way on to the nearest charger, projected from its
    learned consumption, must stay above the critical level of its policy. `energy`: the
    cycle's facts, which must include `vehicle` (read here when not given)."""
    if vehicle.battery_charge is None or not route:
        return None
    facts = energy if energy is not None else read_dispatch_energy(vehicles=[vehicle])
    chargers = facts.charger_nodes(vehicle.map_id)
    metres = graph.path_length(route) + _to_nearest_charger(route[-1], chargers, graph)
    model = consumption_of(facts.energy.get(vehicle.pk))
    use = model.project(metres=metres, standing_seconds=actions * ACTION_SECONDS)
    levels = facts.book.for_vehicle(vehicle)
    return levels.job_refusal(vehicle.battery_charge, use, model.per_hour)


def _to_nearest_charger(node: str, chargers: list[str], graph: RoutingGraph) -> float:
    distances = []
    for charger_node in chargers:
        try:
            distances.append(graph.distances_to(charger_node).get(node, math.inf))
        except NoRouteError:
            continue
    finite = [d for d in distances if math.isfinite(d)]
    return min(finite, default=0.0)


def projected_charge(*, vehicle: Vehicle, metres: float, actions: int = 2) -> float | None:
    """The charge `vehicle` would have after a job of `metres` with `actions` load actions."""
    if vehicle.battery_charge is None:
        return None
    model = consumption_of(VehicleEnergy.objects.filter(vehicle=vehicle).first())
    return vehicle.battery_charge - model.project(
        metres=metres, standing_seconds=actions * ACTION_SECONDS
    )


ACTION_SECONDS = 10.0  # a pick or drop, for the standing share of a job's projection


def busy_vehicle_ids() -> set[int]:
    return set(Vehicle.objects.filter(**BUSY_LOOKUP).values_list("pk", flat=True))


def list_open_sessions() -> QuerySet[ChargeSession]:
    return ChargeSession.objects.filter(status__in=OPEN_SESSION_STATUSES).select_related(
        "vehicle", "charger__station__node", "charger__station__map"
    )


def list_charge_jobs() -> list[dict[str, Any]]:
    """Charge sessions `control` drives now (assigned or driving), as plain data."""
    rows = ChargeSession.objects.filter(
        status__in=[Status.ASSIGNED, Status.DRIVING], charger__isnull=False
    ).select_related("charger__station__map")
    return [
        {
            "session": s.pk,
            "vehicle": s.vehicle_id,
            "route": list(s.route),
            "vda_order_id": s.vda_order_id,
            "map_id": s.charger.station.map.map_id,
            "station": s.charger.station.station_id,
        }
        for s in rows
        if s.charger is not None and s.route
    ]


def booked_points() -> set[tuple[int, int]]:
    return set(booked_vehicles())


def battery_history(*, vehicle: Vehicle, limit: int = 500) -> QuerySet[BatterySample]:
    return BatterySample.objects.filter(vehicle=vehicle).order_by("-at")[:limit]


def open_alerts() -> QuerySet[BatteryAlert]:
    return BatteryAlert.objects.filter(resolved_at__isnull=True).select_related("vehicle")


def booked_vehicles() -> dict[tuple[int, int], int]:
    """(charger, point) -> the vehicle holding it."""
    return {
        (charger, point or 0): vehicle
        for charger, point, vehicle in ChargeSession.objects.filter(
            status__in=BOOKED_STATUSES, charger__isnull=False
        ).values_list("charger_id", "point", "vehicle_id")
    }


@dataclass
class VehicleBattery:
    """One row of the battery overview (page and API)."""

    pk: int
    vehicle: Vehicle
    battery_charge: float | None
    charging: bool
    band: str | None
    drain_per_metre: float | None
    drain_per_hour: float | None
    charge_cycles: float
    health: float | None
    session: int | None
    session_status: str | None

    def __str__(self) -> str:
        return str(self.vehicle)


def list_vehicle_energy() -> list[VehicleBattery]:
    book = get_policy_book()
    energy = {e.vehicle_id: e for e in VehicleEnergy.objects.all()}
    sessions = {
        s.vehicle_id: s for s in ChargeSession.objects.filter(status__in=OPEN_SESSION_STATUSES)
    }
    rows = []
    for vehicle in Vehicle.objects.order_by("manufacturer", "serial_number"):
        learned, session = energy.get(vehicle.pk), sessions.get(vehicle.pk)
        per_hour = learned.drain_per_hour if learned else None
        band = (
            None
            if vehicle.battery_charge is None
            else str(book.for_vehicle(vehicle).band(vehicle.battery_charge, per_hour))
        )
        rows.append(
            VehicleBattery(
                pk=vehicle.pk,
                vehicle=vehicle,
                battery_charge=vehicle.battery_charge,
                charging=vehicle.charging,
                band=band,
                drain_per_metre=learned.drain_per_metre if learned else None,
                drain_per_hour=per_hour,
                charge_cycles=learned.charge_cycles if learned else 0.0,
                health=learned.health if learned else None,
                session=session.pk if session else None,
                session_status=session.status if session else None,
            )
        )
    return rows
