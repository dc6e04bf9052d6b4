"""Reads for the report pages and CSV exports, from the aggregated tables only."""

from collections import defaultdict
from dataclasses import dataclass
from datetime import date, datetime, time, timedelta
from functools import cached_property

from django.conf import settings
from django.db.models import QuerySet, Sum
from django.utils import timezone

from reports.models import (
    LEAD_TIME_BUCKETS,
    LEAD_TIME_STAGES,
    ErrorCount,
    LeadTimeCount,
    VehicleHour,
)
from reports.services import TIME_COLUMNS
from robots.models import Vehicle

STAGE_NAMES = {
    "waiting": "created → assigned",
    "approach": "assigned → started",
    "execution": "started → finished",
    "total": "created → finished",
}


@dataclass(frozen=True)
class ReportFilter:
    """A date range (local dates, both included) and optionally some vehicles."""

    start: date
    end: date
    vehicle_ids: tuple[int, ...] = ()

    @cached_property
    def since(self) -> datetime:
        return timezone.make_aware(datetime.combine(self.start, time.min))

    @cached_property
    def until(self) -> datetime:
        return timezone.make_aware(datetime.combine(self.end + timedelta(days=1), time.min))


def _hours(report: ReportFilter) -> QuerySet[VehicleHour]:
    rows = VehicleHour.objects.filter(hour__gte=report.since, hour__lt=report.until)
    return rows.filter(vehicle__in=report.vehicle_ids) if report.vehicle_ids else rows


def _days(rows: QuerySet[LeadTimeCount] | QuerySet[ErrorCount], report: ReportFilter) -> QuerySet:  # type: ignore[type-arg]
    rows = rows.filter(day__gte=report.start, day__lte=report.end)
    return rows.filter(vehicle__in=report.vehicle_ids) if report.vehicle_ids else rows


@dataclass(frozen=True)
class HourPoint:
    hour: datetime
    finished: int
    failed: int
    cancelled: int
    with_deadline: int = 0
    on_time: int = 0


def throughput_by_hour(report: ReportFilter) -> list[HourPoint]:
    """Orders ended per hour, every hour of the range (zeros included), in local time."""
    totals = {
        row["hour"]: row
        for row in _hours(report)
        .values("hour")
        .annotate(
            f=Sum("finished"),
            x=Sum("failed"),
            c=Sum("cancelled"),
            d=Sum("with_deadline"),
            t=Sum("on_time"),
        )
        .order_by()
    }
    points, hour = [], report.since
    while hour < report.until:
        row = totals.get(hour, {})
        points.append(
            HourPoint(
                timezone.localtime(hour),
                *(row.get(key, 0) for key in ("f", "x", "c", "d", "t")),
            )
        )
        hour += timedelta(hours=1)
    return points


@dataclass(frozen=True)
class DayPoint:
    day: date
    finished: int
    failed: int


def throughput_by_day(points: list[HourPoint]) -> list[DayPoint]:
    totals: dict[date, list[int]] = defaultdict(lambda: [0, 0])
    for point in points:
        totals[point.hour.date()][0] += point.finished
        totals[point.hour.date()][1] += point.failed
    return [DayPoint(day, done, failed) for day, (done, failed) in sorted(totals.items())]


def hour_of_day_profile(points: list[HourPoint]) -> list[float]:
    """Average orders finished in each hour of the day (0–23) over the range."""
    sums, days = [0] * 24, [0] * 24
    for point in points:
        sums[point.hour.hour] += point.finished
        days[point.hour.hour] += 1
    return [total / count if count else 0.0 for total, count in zip(sums, days, strict=True)]


@dataclass(frozen=True)
class ShiftRow:
    day: date
    shift: str
    finished: int
    failed: int


def shift_of(moment: datetime) -> tuple[date, str]:
    """The working day and shift a local time belongs to (a night shift keeps its start day)."""
    shifts = sorted(settings.REPORT_SHIFTS, key=lambda shift: shift[1])
    current = next((s for s in reversed(shifts) if moment.hour >= s[1]), None)
    if current is None:  # before the first shift starts: the last shift of the day before
        return moment.date() - timedelta(days=1), shifts[-1][0]
    return moment.date(), current[0]


def throughput_by_shift(points: list[HourPoint]) -> list[ShiftRow]:
    totals: dict[tuple[date, str], list[int]] = defaultdict(lambda: [0, 0])
    for point in points:
        key = shift_of(point.hour)
        totals[key][0] += point.finished
        totals[key][1] += point.failed
    order = [name for name, _ in sorted(settings.REPORT_SHIFTS, key=lambda shift: shift[1])]
    rows = sorted(totals.items(), key=lambda item: (item[0][0], order.index(item[0][1])))
    return [ShiftRow(day, shift, done, failed) for (day, shift), (done, failed) in rows]


@dataclass(frozen=True)
class Punctuality:
    with_deadline: int
    on_time: int

    @property
    def rate(self) -> float | None:
        return self.on_time / self.with_deadline if self.with_deadline else None


def punctuality(points: list[HourPoint]) -> Punctuality:
    return Punctuality(sum(p.with_deadline for p in points), sum(p.on_time for p in points))


@dataclass(frozen=True)
class StageDistribution:
    """A lead-time stage's histogram with its count, mean and percentile bounds."""

    stage: str
    counts: list[int]
    total_s: float

    @property
    def name(self) -> str:
        return STAGE_NAMES[self.stage]

    @property
    def count(self) -> int:
        return sum(self.counts)

    @property
    def mean_s(self) -> float | None:
        return self.total_s / self.count if self.count else None

    @property
    def percentile_50(self) -> str:
        return self.percentile(0.5)

    @property
    def percentile_90(self) -> str:
        return self.percentile(0.9)

    def percentile(self, share: float) -> str:
        """The bucket bound under which `share` of the orders fall ("≤ 60 s", "> 7200 s")."""
        if not self.count:
            return "–"
        running = 0
        for index, count in enumerate(self.counts):
            running += count
            if running >= share * self.count:
                return bucket_label(index)
        return bucket_label(len(self.counts) - 1)


def bucket_label(index: int) -> str:
    if index < len(LEAD_TIME_BUCKETS):
        return f"≤ {LEAD_TIME_BUCKETS[index]} s"
    return f"> {LEAD_TIME_BUCKETS[-1]} s"


def lead_times(report: ReportFilter) -> list[StageDistribution]:
    """Each stage's distribution over the range: one grouped query."""
    counts = {stage: [0] * (len(LEAD_TIME_BUCKETS) + 1) for stage in LEAD_TIME_STAGES}
    totals: dict[str, float] = defaultdict(float)
    rows = (
        _days(LeadTimeCount.objects.all(), report)
        .values("stage", "bucket")
        .annotate(n=Sum("count"), s=Sum("seconds"))
        .order_by()
    )
    for row in rows:
        if row["stage"] in counts and row["bucket"] < len(counts[row["stage"]]):
            counts[row["stage"]][row["bucket"]] += row["n"]
            totals[row["stage"]] += row["s"]
    return [StageDistribution(stage, counts[stage], totals[stage]) for stage in LEAD_TIME_STAGES]


@dataclass(frozen=True)
class VehicleUse:
    """One vehicle's time by state, distance, energy and finished orders over the range."""

    vehicle: str
    seconds: dict[str, float]
    distance_m: float
    energy_pct: float
    finished: int

    @property
    def observed_s(self) -> float:
        return sum(self.seconds.values())

    def share(self, column: str) -> float:
        return self.seconds[column] / self.observed_s if self.observed_s else 0.0

    @property
    def shares(self) -> list[float]:
        """Percent of the observed time per state, in TIME_COLUMNS order."""
        return [self.share(column) * 100 for column in TIME_COLUMNS]


def utilisation(report: ReportFilter) -> list[VehicleUse]:
    sums = {column: Sum(column) for column in (*TIME_COLUMNS, "distance_m", "energy_pct")}
    rows = (
        _hours(report)
        .filter(vehicle__isnull=False)
        .values("vehicle")
        .annotate(**sums, done=Sum("finished"))
        .order_by()
    )
    names = _vehicle_names({row["vehicle"] for row in rows})
    uses = [
        VehicleUse(
            vehicle=names.get(row["vehicle"], str(row["vehicle"])),
            seconds={column: row[column] or 0.0 for column in TIME_COLUMNS},
            distance_m=row["distance_m"] or 0.0,
            energy_pct=row["energy_pct"] or 0.0,
            finished=row["done"] or 0,
        )
        for row in rows
    ]
    return sorted(uses, key=lambda use: use.vehicle)


@dataclass(frozen=True)
class ErrorTally:
    vehicle: str
    error_type: str
    count: int


def errors(report: ReportFilter) -> list[ErrorTally]:
    """Error occurrences per vehicle and type, most frequent first: one grouped query."""
    rows = (
        _days(ErrorCount.objects.all(), report)
        .values("vehicle", "error_type")
        .annotate(n=Sum("count"))
        .order_by("-n", "vehicle", "error_type")
    )
    names = _vehicle_names({row["vehicle"] for row in rows if row["vehicle"] is not None})
    return [ErrorTally(names.get(row["vehicle"], "–"), row["error_type"], row["n"]) for row in rows]


def _vehicle_names(ids: set[int]) -> dict[int, str]:
    return {vehicle.pk: str(vehicle) for vehicle in Vehicle.objects.filter(pk__in=ids)}
