"""Writes of the reports app: the order roll-up and the vehicle sampler, both run by Celery.

Both add to the aggregated tables through a `Ledger`, which collects deltas in memory and writes
them in a few bulk statements. The roll-up reads each ended order once (a watermark on
`finished_at`, moved under a row lock so overlapping runs never count twice); the sampler turns
the time since its last look at each vehicle into busy/idle/charging/error/offline seconds.
"""

import bisect
import math
from collections import Counter, defaultdict
from collections.abc import Iterable, Sequence
from dataclasses import dataclass, field
from datetime import UTC, date, datetime, timedelta
from typing import Any

from django.db import transaction
from django.db.models import Model
from django.utils import timezone

from fleet.bulk import update_rows
from orders.models import TransportOrder
from reports.models import (
    LEAD_TIME_BUCKETS,
    ErrorCount,
    LeadTimeCount,
    RollupMark,
    SamplerMark,
    VehicleHour,
)
from robots.models import Vehicle

# An order's finished_at is stamped just before its transaction commits: leave it that long.
SETTLE = timedelta(seconds=5)
# A longer gap between samples (sampler stopped) is not attributed to any state.
MAX_SAMPLE_GAP = timedelta(seconds=60)
TIME_COLUMNS = ("busy_s", "idle_s", "charging_s", "error_s", "offline_s")
COUNT_COLUMNS = ("finished", "failed", "cancelled", "with_deadline", "on_time")
HOUR_COLUMNS = (*COUNT_COLUMNS, *TIME_COLUMNS, "distance_m", "energy_pct")
WORKING_MODES = {"AUTOMATIC", "SEMIAUTOMATIC"}


@dataclass(frozen=True)
class EndedOrder:
    """The fields of an ended transport order that the reports use."""

    vehicle_id: int | None
    status: str
    created_at: datetime
    assigned_at: datetime | None
    started_at: datetime | None
    finished_at: datetime
    deadline: datetime | None


@dataclass(frozen=True)
class VehicleSample:
    """One look at a vehicle's live state (the registry's snapshot)."""

    vehicle_id: int
    at: datetime
    state: str  # busy, idle, charging, error or offline
    x: float | None = None
    y: float | None = None
    map_id: str = ""
    battery_charge: float | None = None
    error_types: tuple[str, ...] = ()


def hour_of(moment: datetime) -> datetime:
    return moment.astimezone(UTC).replace(minute=0, second=0, microsecond=0)


def day_of(moment: datetime) -> date:
    return timezone.localtime(moment).date()


def bucket_of(seconds: float) -> int:
    """Index of the lead-time bucket (the last one is everything above the largest bound)."""
    return bisect.bisect_left(LEAD_TIME_BUCKETS, seconds)


def stage_durations(order: EndedOrder) -> dict[str, float]:
    """Seconds of each lead-time stage of a finished order (stages without stamps left out)."""
    spans = {
        "waiting": (order.created_at, order.assigned_at),
        "approach": (order.assigned_at, order.started_at),
        "execution": (order.started_at, order.finished_at),
        "total": (order.created_at, order.finished_at),
    }
    return {
        stage: max(0.0, (end - begin).total_seconds())
        for stage, (begin, end) in spans.items()
        if begin is not None and end is not None
    }


@dataclass
class Ledger:
    """Deltas for the aggregated tables, collected in memory and written by `apply`."""

    hours: dict[tuple[datetime, int | None], dict[str, float]] = field(
        default_factory=lambda: defaultdict(lambda: defaultdict(float))
    )
    # (day, vehicle, stage, bucket) → [orders, seconds]
    lead_times: dict[tuple[date, int | None, str, int], list[float]] = field(
        default_factory=lambda: defaultdict(lambda: [0, 0.0])
    )
    errors: dict[tuple[date, int | None], Counter[str]] = field(
        default_factory=lambda: defaultdict(Counter)
    )

    def add_order(self, order: EndedOrder) -> None:
        row = self.hours[(hour_of(order.finished_at), order.vehicle_id)]
        if order.status == TransportOrder.Status.FINISHED:
            row["finished"] += 1
            if order.deadline is not None:
                row["with_deadline"] += 1
                row["on_time"] += order.finished_at <= order.deadline
            day = day_of(order.finished_at)
            for stage, seconds in stage_durations(order).items():
                cell = self.lead_times[(day, order.vehicle_id, stage, bucket_of(seconds))]
                cell[0] += 1
                cell[1] += seconds
        elif order.status == TransportOrder.Status.FAILED:
            row["failed"] += 1
        elif order.status == TransportOrder.Status.CANCELLED:
            row["cancelled"] += 1

    def add_sample(self, sample: VehicleSample, previous: SamplerMark | None) -> None:
        """Attribute the time since the previous sample to the state seen now."""
        seen_before = set(previous.error_types or []) if previous else set()
        for error_type in set(sample.error_types) - seen_before:
            self.errors[(day_of(sample.at), sample.vehicle_id)][error_type] += 1
        if previous is None:
            return
        elapsed = min(sample.at - previous.at, MAX_SAMPLE_GAP).total_seconds()
        if elapsed <= 0:
            return
        row = self.hours[(hour_of(sample.at), sample.vehicle_id)]
        row[f"{sample.state}_s"] += elapsed
        if sample.map_id == previous.map_id and None not in (
            sample.x,
            sample.y,
            previous.x,
            previous.y,
        ):
            row["distance_m"] += math.dist((sample.x, sample.y), (previous.x, previous.y))  # type: ignore[arg-type]
        if sample.battery_charge is not None and previous.battery_charge is not None:
            row["energy_pct"] += max(0.0, previous.battery_charge - sample.battery_charge)

    def apply(self) -> None:
        """Add the deltas to the tables: a read, a bulk update and a bulk insert per table."""
        self._apply_hours()
        self._apply_lead_times()
        self._apply_errors()

    def _apply_hours(self) -> None:
        if not self.hours:
            return
        existing = {
            (row.hour, row.vehicle_id): row
            for row in VehicleHour.objects.filter(hour__in={hour for hour, _ in self.hours})
        }
        changed, created = [], []
        for (hour, vehicle_id), delta in self.hours.items():
            row = existing.get((hour, vehicle_id))
            if row is None:
                row = VehicleHour(hour=hour, vehicle_id=vehicle_id)
                created.append(row)
            else:
                changed.append(row)
            for column, value in delta.items():
                total = getattr(row, column) + value
                setattr(row, column, round(total) if column in COUNT_COLUMNS else total)
        update_rows(VehicleHour, [_values(row, HOUR_COLUMNS) for row in changed], HOUR_COLUMNS)
        VehicleHour.objects.bulk_create(created, batch_size=500)

    def _apply_lead_times(self) -> None:
        if not self.lead_times:
            return
        existing = {
            (row.day, row.vehicle_id, row.stage, row.bucket): row
            for row in LeadTimeCount.objects.filter(day__in={key[0] for key in self.lead_times})
        }
        changed, created = [], []
        for key, (count, seconds) in self.lead_times.items():
            row = existing.get(key)
            if row is None:
                day, vehicle_id, stage, bucket = key
                row = LeadTimeCount(day=day, vehicle_id=vehicle_id, stage=stage, bucket=bucket)
                created.append(row)
            else:
                changed.append(row)
            row.count += int(count)
            row.seconds += seconds
        LeadTimeCount.objects.bulk_update(changed, ["count", "seconds"], batch_size=500)
        LeadTimeCount.objects.bulk_create(created, batch_size=500)

    def _apply_errors(self) -> None:
        if not self.errors:
            return
        existing = {
            (row.day, row.vehicle_id, row.error_type): row
            for row in ErrorCount.objects.filter(day__in={day for day, _ in self.errors})
        }
        changed, created = [], []
        for (day, vehicle_id), by_type in self.errors.items():
            for error_type, count in by_type.items():
                row = existing.get((day, vehicle_id, error_type))
                if row is None:
                    row = ErrorCount(day=day, vehicle_id=vehicle_id, error_type=error_type)
                    created.append(row)
                else:
                    changed.append(row)
                row.count += count
        ErrorCount.objects.bulk_update(changed, ["count"], batch_size=500)
        ErrorCount.objects.bulk_create(created, batch_size=500)


def ended_orders(since: datetime, until: datetime) -> Iterable[EndedOrder]:
    rows = (
        TransportOrder.objects.filter(finished_at__gt=since, finished_at__lte=until)
        .order_by()
        .values_list(
            "vehicle_id",
            "status",
            "created_at",
            "assigned_at",
            "started_at",
            "finished_at",
            "deadline",
        )
    )
    for vehicle_id, status, created, assigned, started, finished, deadline in rows.iterator(
        chunk_size=2000
    ):
        assert finished is not None  # filtered above
        yield EndedOrder(vehicle_id, status, created, assigned, started, finished, deadline)


def roll_up_orders(*, now: datetime | None = None) -> int:
    """Add every order that ended since the last roll-up to the tables; return how many.

    Exactly once per order: the watermark moves in the same transaction as the figures, under a
    row lock that makes an overlapping run wait and then start where this one stopped.
    """
    until = (now or timezone.now()) - SETTLE
    with transaction.atomic():
        RollupMark.objects.get_or_create(pk=1, defaults={"at": datetime(2000, 1, 1, tzinfo=UTC)})
        mark = RollupMark.objects.select_for_update().get(pk=1)
        if until <= mark.at:
            return 0
        ledger = Ledger()
        count = 0
        for order in ended_orders(mark.at, until):
            ledger.add_order(order)
            count += 1
        ledger.apply()
        mark.at = until
        mark.save(update_fields=["at"])
    return count


def classify(vehicle: dict[str, Any], busy: set[int]) -> str:
    """busy, idle, charging, error or offline, from a vehicle's snapshot."""
    if vehicle["connection"] != Vehicle.Connection.ONLINE:
        return "offline"
    fatal = any(e.get("errorLevel") == "FATAL" for e in vehicle["errors"] or [])
    if fatal or (vehicle["operating_mode"] and vehicle["operating_mode"] not in WORKING_MODES):
        return "error"
    if vehicle["charging"]:
        return "charging"
    if vehicle["pk"] in busy or vehicle["driving"]:
        return "busy"
    return "idle"


def _values(row: Model, fields: Sequence[str]) -> dict[str, Any]:
    """`row`'s pk and `fields`, for `fleet.bulk.update_rows`."""
    return {"pk": row.pk} | {name: getattr(row, name) for name in fields}


def sample_vehicles(*, now: datetime | None = None) -> int:
    """Look at every vehicle's snapshot once and add the time since the last look; return count."""
    now = now or timezone.now()
    busy = set(
        TransportOrder.objects.filter(
            status__in=TransportOrder.ACTIVE_STATUSES, vehicle__isnull=False
        ).values_list("vehicle_id", flat=True)
    )
    columns = ["pk", "connection", "errors", "operating_mode", "charging", "driving", "x", "y"]
    vehicles = Vehicle.objects.values(*columns, "map_id", "battery_charge")
    with transaction.atomic():
        marks = {m.vehicle_id: m for m in SamplerMark.objects.select_for_update()}
        ledger = Ledger()
        changed: list[SamplerMark] = []
        created: list[SamplerMark] = []
        for vehicle in vehicles:
            sample = VehicleSample(
                vehicle_id=vehicle["pk"],
                at=now,
                state=classify(vehicle, busy),
                x=vehicle["x"],
                y=vehicle["y"],
                map_id=vehicle["map_id"],
                battery_charge=vehicle["battery_charge"],
                error_types=tuple(sorted({str(e.get("errorType", "")) for e in vehicle["errors"]})),
            )
            previous = marks.get(sample.vehicle_id)
            if previous is not None and previous.at >= now:
                continue  # an overlapping run already looked at this vehicle
            ledger.add_sample(sample, previous)
            mark = previous or SamplerMark(vehicle_id=sample.vehicle_id)
            (changed if previous else created).append(mark)
            mark.at, mark.x, mark.y, mark.map_id = now, sample.x, sample.y, sample.map_id
            mark.battery_charge, mark.error_types = sample.battery_charge, list(sample.error_types)
        ledger.apply()
        fields = ["at", "x", "y", "map_id", "battery_charge", "error_types"]
        update_rows(SamplerMark, [_values(mark, fields) for mark in changed], fields)
        SamplerMark.objects.bulk_create(created, batch_size=500)
    return len(changed) + len(created)
