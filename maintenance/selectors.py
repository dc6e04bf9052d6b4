"""Reads of the maintenance app: who is out of service and why, due work, error statistics."""

from collections import Counter
from collections.abc import Iterable
from dataclasses import dataclass, field

from django.db.models import Count, QuerySet

from maintenance.models import (
    OPEN_MOVES,
    OPEN_WORK,
    ErrorRecord,
    ServiceEvent,
    ServiceMove,
    ServicePlan,
    VehicleCounters,
    WorkOrder,
)
from maps.models import VehicleType
from robots.models import Vehicle


def out_of_service(*, vehicle_ids: Iterable[int]) -> dict[int, str]:
    """Vehicles dispatch must not use, with the reason: taken out of service by staff, or an
    open work order that takes them out of service."""
    ids = list(vehicle_ids)
    reasons: dict[int, str] = {}
    for vehicle_id, title, pk in (
        WorkOrder.objects.filter(
            vehicle_id__in=ids, status__in=OPEN_WORK, takes_out_of_service=True
        )
        .order_by("due_at")
        .values_list("vehicle_id", "title", "pk")
    ):
        reasons.setdefault(vehicle_id, f"in maintenance (work order {pk}: {title})"[:120])
    for vehicle_id, reason in VehicleCounters.objects.filter(
        vehicle_id__in=ids, out_of_service=True
    ).values_list("vehicle_id", "out_of_service_reason"):
        reasons[vehicle_id] = f"out of service: {reason}"[:120]
    return reasons


def list_move_jobs() -> list[dict[str, object]]:
    """Moves `control` drives now (assigned or driving), as plain data."""
    moves = ServiceMove.objects.filter(status__in=OPEN_MOVES).select_related("station__map")
    return [
        {
            "move": m.pk,
            "vehicle": m.vehicle_id,
            "route": list(m.route),
            "vda_order_id": m.vda_order_id,
            "map_id": m.station.map.map_id,
            "station": m.station.station_id,
        }
        for m in moves
        if m.route
    ]


def plan_vehicles(*, plan: ServicePlan) -> list[Vehicle]:
    """The vehicles a plan applies to: its vehicle, its type's vehicles, or all."""
    if plan.vehicle_id is not None:
        return list(Vehicle.objects.filter(pk=plan.vehicle_id))
    vehicles = list(Vehicle.objects.all())
    if plan.vehicle_type is None:
        return vehicles
    return [v for v in vehicles if _is_of_type(v, plan.vehicle_type)]


def _is_of_type(vehicle: Vehicle, vehicle_type: VehicleType) -> bool:
    series = str(((vehicle.factsheet or {}).get("typeSpecification") or {}).get("seriesName") or "")
    if not series:
        return False
    if vehicle_type.type_id == f"{vehicle.manufacturer}.{series}":
        return True
    return vehicle_type.series_name == series and vehicle_type.manufacturer in (
        "",
        vehicle.manufacturer,
    )


def list_open_work_orders() -> QuerySet[WorkOrder]:
    return WorkOrder.objects.filter(status__in=OPEN_WORK).select_related("vehicle", "plan")


def list_overdue_work_orders() -> QuerySet[WorkOrder]:
    return list_open_work_orders().filter(events__kind=ServiceEvent.Kind.OVERDUE).distinct()


def service_history(*, vehicle: Vehicle, limit: int = 200) -> QuerySet[ServiceEvent]:
    return ServiceEvent.objects.filter(vehicle=vehicle).select_related("work_order")[:limit]


@dataclass
class ErrorStats:
    """A vehicle's error history in figures."""

    total: int = 0
    fatal: int = 0
    open: int = 0
    operating_hours: float = 0.0
    mtbf_hours: float | None = None  # operating hours per FATAL error (None: none so far)
    top_types: list[tuple[str, int]] = field(default_factory=list)
    by_level: dict[str, int] = field(default_factory=dict)


def error_stats(*, vehicle: Vehicle, top: int = 5) -> ErrorStats:
    records = ErrorRecord.objects.filter(vehicle=vehicle)
    levels = Counter(
        dict(records.values("error_level").annotate(n=Count("pk")).values_list("error_level", "n"))
    )
    counters = VehicleCounters.objects.filter(vehicle=vehicle).first()
    hours = counters.operating_hours if counters else 0.0
    fatal = levels.get("FATAL", 0)
    return ErrorStats(
        total=sum(levels.values()),
        fatal=fatal,
        open=records.filter(ended_at__isnull=True).count(),
        operating_hours=round(hours, 2),
        mtbf_hours=round(hours / fatal, 2) if fatal else None,
        top_types=list(
            records.values("error_type")
            .annotate(n=Count("pk"))
            .order_by("-n", "error_type")
            .values_list("error_type", "n")[:top]
        ),
        by_level=dict(levels),
    )
