"""Service plans, work orders and taking vehicles out of service and back."""

from datetime import datetime, timedelta
from typing import Any

from django.contrib.auth.models import AbstractBaseUser, AnonymousUser, User
from django.core.files.uploadedfile import UploadedFile
from django.db import IntegrityError, transaction
from django.utils import timezone

from fleet.exceptions import DomainError, InvalidRequestError
from maintenance.models import (
    OPEN_WORK,
    PlanBaseline,
    ServiceEvent,
    ServicePlan,
    VehicleCounters,
    WorkOrder,
    WorkOrderAttachment,
)
from maintenance.selectors import plan_vehicles
from maintenance.services.moves import send_to_station
from robots.models import Vehicle

Kind = ServiceEvent.Kind
Status = WorkOrder.Status
User_ = AbstractBaseUser | AnonymousUser | None


def _user(by: User_) -> User | None:
    return by if isinstance(by, User) else None


def _event(
    vehicle_id: int,
    kind: str,
    detail: str = "",
    work_order: WorkOrder | None = None,
    at: datetime | None = None,
) -> None:
    ServiceEvent.objects.create(
        vehicle_id=vehicle_id,
        kind=kind,
        detail=detail[:300],
        work_order=work_order,
        at=at or timezone.now(),
    )


def counters_of(vehicle_id: int) -> VehicleCounters:
    return VehicleCounters.objects.get_or_create(vehicle_id=vehicle_id)[0]


def _reading(counters: VehicleCounters) -> dict[str, float]:
    return {
        "hours": round(counters.operating_hours, 3),
        "km": round(counters.distance_km, 3),
        "cycles": round(counters.charge_cycles, 3),
    }


def check_service_plans(*, now: datetime | None = None) -> list[WorkOrder]:
    """Fire a work order for every (plan, vehicle) whose interval since the last service has
    been reached, and note overdue work orders. Returns the new work orders."""
    now = now or timezone.now()
    created = []
    for plan in ServicePlan.objects.filter(is_active=True).select_related("vehicle_type"):
        for vehicle in plan_vehicles(plan=plan):
            counters = counters_of(vehicle.pk)
            baseline, _ = PlanBaseline.objects.get_or_create(
                plan=plan,
                vehicle=vehicle,
                defaults={**_reading(counters), "since": now},
            )
            trigger = _trigger(plan, counters, baseline, now)
            if trigger is not None:
                work_order = _fire(plan, vehicle, counters, trigger, now)
                if work_order is not None:
                    created.append(work_order)
    _note_overdue(now)
    return created


def _trigger(
    plan: ServicePlan, counters: VehicleCounters, baseline: PlanBaseline, now: datetime
) -> str | None:
    reading = _reading(counters)
    checks = [
        (plan.interval_hours, reading["hours"] - baseline.hours, "operating hours", "h"),
        (plan.interval_km, reading["km"] - baseline.km, "distance", "km"),
        (plan.interval_cycles, reading["cycles"] - baseline.cycles, "charge cycles", ""),
        (
            plan.interval_days,
            (now - baseline.since).total_seconds() / 86400.0,
            "calendar days",
            "d",
        ),
    ]
    for interval, used, name, unit in checks:
        if interval is not None and used >= interval:
            return f"{name}: {used:.1f}{unit} since last service (interval {interval:g}{unit})"
    return None


def _fire(
    plan: ServicePlan, vehicle: Vehicle, counters: VehicleCounters, trigger: str, now: datetime
) -> WorkOrder | None:
    try:
        with transaction.atomic():
            work_order = WorkOrder.objects.create(
                vehicle=vehicle,
                plan=plan,
                title=plan.name,
                status=Status.DUE,
                takes_out_of_service=plan.takes_out_of_service,
                trigger=trigger,
                counters=_reading(counters),
                notes=plan.instructions,
                due_at=now,
            )
            _event(vehicle.pk, Kind.WORK_ORDER_DUE, trigger, work_order, now)
            if plan.takes_out_of_service:
                _event(
                    vehicle.pk, Kind.OUT_OF_SERVICE, f"work order {work_order.pk}", work_order, now
                )
    except IntegrityError:
        return None  # this plan's work order for the vehicle is open already
    return work_order


def _note_overdue(now: datetime) -> None:
    for work_order in WorkOrder.objects.filter(status__in=OPEN_WORK).select_related("plan"):
        grace = work_order.plan.grace_days if work_order.plan else 1.0
        if now <= work_order.due_at + timedelta(days=grace):
            continue
        if not ServiceEvent.objects.filter(work_order=work_order, kind=Kind.OVERDUE).exists():
            _event(
                work_order.vehicle_id,
                Kind.OVERDUE,
                f"due {work_order.due_at:%Y-%m-%d}",
                work_order,
                now,
            )


def create_work_order(
    *,
    vehicle: Vehicle,
    title: str,
    takes_out_of_service: bool = False,
    notes: str = "",
    by: User_ = None,
) -> WorkOrder:
    """Open a work order by hand (corrective maintenance)."""
    if not title.strip():
        raise InvalidRequestError("a work order needs a title")
    with transaction.atomic():
        work_order = WorkOrder.objects.create(
            vehicle=vehicle,
            title=title.strip()[:200],
            status=Status.OPEN,
            takes_out_of_service=takes_out_of_service,
            counters=_reading(counters_of(vehicle.pk)),
            notes=notes,
            technician=_user(by),
            due_at=timezone.now(),
        )
        if takes_out_of_service:
            _event(vehicle.pk, Kind.OUT_OF_SERVICE, f"work order {work_order.pk}", work_order)
    return work_order


_NEXT = {
    Status.OPEN: {Status.DUE},
    Status.IN_PROGRESS: {Status.DUE, Status.OPEN},
    Status.DONE: {Status.DUE, Status.OPEN, Status.IN_PROGRESS},
}


@transaction.atomic
def advance_work_order(
    *,
    work_order: WorkOrder,
    status: str,
    notes: str = "",
    parts: list[dict[str, Any]] | None = None,
    by: User_ = None,
) -> WorkOrder:
    """Move a work order on (open, in progress, done), adding technician notes and parts (the
    same status only adds them). Done resets the plan's baseline to the vehicle's counters now;
    the vehicle is back in service when no other open work order holds it."""
    work_order = WorkOrder.objects.select_for_update().get(pk=work_order.pk)
    if status not in Status.values:
        raise InvalidRequestError(f"unknown work order status {status!r}")
    unchanged = status == work_order.status and status != Status.DONE
    if not unchanged and (status not in _NEXT or work_order.status not in _NEXT[Status(status)]):
        raise DomainError(f"work order {work_order.pk} is {work_order.status}, cannot go {status}")
    parts = parts or []
    for part in parts:
        if not isinstance(part, dict) or not str(part.get("part", "")).strip():
            raise InvalidRequestError("each part needs a name: {'part': ..., 'qty': n}")
    now = timezone.now()
    work_order.status = status
    if notes.strip():
        stamp = now.strftime("%Y-%m-%d %H:%M")
        work_order.notes = f"{work_order.notes}\n[{stamp}] {notes.strip()}".strip()
    work_order.parts = [*work_order.parts, *parts]
    if _user(by) is not None:
        work_order.technician = _user(by)
    if unchanged:
        work_order.save()
        return work_order
    if status == Status.IN_PROGRESS:
        work_order.started_at = now
        _event(work_order.vehicle_id, Kind.WORK_ORDER_STARTED, work_order.title, work_order, now)
    if status == Status.DONE:
        work_order.done_at = now
        work_order.started_at = work_order.started_at or now
        _event(work_order.vehicle_id, Kind.WORK_ORDER_DONE, work_order.title, work_order, now)
        if work_order.plan_id is not None:
            reading = _reading(counters_of(work_order.vehicle_id))
            PlanBaseline.objects.update_or_create(
                plan_id=work_order.plan_id,
                vehicle_id=work_order.vehicle_id,
                defaults={**reading, "since": now},
            )
    work_order.save()
    if (
        status == Status.DONE
        and work_order.takes_out_of_service
        and not _held(work_order.vehicle_id)
    ):
        _event(
            work_order.vehicle_id,
            Kind.BACK_IN_SERVICE,
            f"work order {work_order.pk} done",
            work_order,
            now,
        )
    return work_order


def _held(vehicle_id: int) -> bool:
    return (
        WorkOrder.objects.filter(
            vehicle_id=vehicle_id, status__in=OPEN_WORK, takes_out_of_service=True
        ).exists()
        or VehicleCounters.objects.filter(vehicle_id=vehicle_id, out_of_service=True).exists()
    )


def add_attachment(
    *, work_order: WorkOrder, file: UploadedFile, description: str = ""
) -> WorkOrderAttachment:
    if file.size is not None and file.size > 20 * 1024 * 1024:
        raise InvalidRequestError("attachments are limited to 20 MB")
    return WorkOrderAttachment.objects.create(
        work_order=work_order, file=file, description=description[:200]
    )


@transaction.atomic
def take_out_of_service(
    *, vehicle: Vehicle, reason: str, by: User_ = None, send_to: str = ""
) -> VehicleCounters:
    """Staff take the vehicle out of service: dispatch gives it no work from now on. Its
    current order (if any) is finished first; its operating mode is left to the vehicle.
    `send_to` "PARK" (or "OTHER", a maintenance bay) also sends it to the nearest free
    station of that kind."""
    if not reason.strip():
        raise InvalidRequestError("say why the vehicle is taken out of service")
    counters = VehicleCounters.objects.select_for_update().get_or_create(vehicle=vehicle)[0]
    if counters.out_of_service:
        raise DomainError(f"{vehicle} is out of service already")
    counters.out_of_service = True
    counters.out_of_service_reason = reason.strip()[:200]
    counters.out_of_service_since = timezone.now()
    counters.save(update_fields=["out_of_service", "out_of_service_reason", "out_of_service_since"])
    _event(vehicle.pk, Kind.OUT_OF_SERVICE, counters.out_of_service_reason)
    if send_to:
        send_to_station(vehicle=vehicle, kinds=(send_to,), reason=f"out of service: {reason}")
    return counters


@transaction.atomic
def return_to_service(*, vehicle: Vehicle, by: User_ = None) -> VehicleCounters:
    """Back in service (open work orders that take it out of service still hold it)."""
    counters = VehicleCounters.objects.select_for_update().get_or_create(vehicle=vehicle)[0]
    if not counters.out_of_service:
        raise DomainError(f"{vehicle} is in service")
    counters.out_of_service = False
    counters.out_of_service_reason = ""
    counters.out_of_service_since = None
    counters.save(update_fields=["out_of_service", "out_of_service_reason", "out_of_service_since"])
    if not _held(vehicle.pk):
        _event(vehicle.pk, Kind.BACK_IN_SERVICE, "returned by staff")
    return counters
