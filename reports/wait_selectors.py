"""Reads of the traffic-wait report, from the rolled-up wait tables only (reports.waits).

Per hour the figures are the whole fleet's (WaitHourCount has no vehicle column, which keeps
it at 24 rows a day at most); per vehicle and on the heatmap the report's vehicle filter applies.
"""

from dataclasses import dataclass
from datetime import datetime, timedelta

from django.db.models import QuerySet, Sum
from django.db.models.functions import ExtractHour, TruncDate
from django.utils import timezone

from maps.models import Edge, Map, Node
from reports.models import WAIT_BUCKETS, WaitDayCount, WaitHourCount, WaitNodeDay
from reports.selectors import ReportFilter, _vehicle_names


def wait_bucket_label(index: int) -> str:
    if index < len(WAIT_BUCKETS):
        return f"≤ {WAIT_BUCKETS[index]} s"
    return f"> {WAIT_BUCKETS[-1]} s"


@dataclass(frozen=True)
class WaitStats:
    """Waits in one group (an hour, an hour of the day, a vehicle): count, mean, p95 bucket."""

    label: str
    counts: tuple[int, ...]
    seconds: float

    @property
    def count(self) -> int:
        return sum(self.counts)

    @property
    def mean_s(self) -> float | None:
        return self.seconds / self.count if self.count else None

    @property
    def p95(self) -> str:
        """The bucket bound under which 95 % of the waits fall (e.g. "≤ 30 s")."""
        if not self.count:
            return "–"
        running = 0
        for index, count in enumerate(self.counts):
            running += count
            if running >= 0.95 * self.count:
                return wait_bucket_label(index)
        return wait_bucket_label(len(self.counts) - 1)


def _stats(label: str, rows: list[tuple[int, int, float]]) -> WaitStats:
    counts = [0] * (len(WAIT_BUCKETS) + 1)
    seconds = 0.0
    for bucket, count, total in rows:
        if 0 <= bucket < len(counts):
            counts[bucket] += count
            seconds += total
    return WaitStats(label, tuple(counts), seconds)


def waits_by_hour(report: ReportFilter) -> list[tuple[datetime, WaitStats]]:
    """The fleet's waits per hour of the range (local time; hours without waits left out)."""
    rows = (
        WaitHourCount.objects.filter(hour__gte=report.since, hour__lt=report.until)
        .values_list("hour", "bucket", "count", "seconds")
        .order_by("hour", "bucket")
    )
    grouped: dict[datetime, list[tuple[int, int, float]]] = {}
    for hour, bucket, count, seconds in rows:
        grouped.setdefault(hour, []).append((bucket, count, seconds))
    return [
        (local, _stats(f"{local:%Y-%m-%d %H}:00", cells))
        for hour, cells in grouped.items()
        for local in [timezone.localtime(hour)]
    ]


def _hour_rows(report: ReportFilter) -> QuerySet[WaitHourCount]:
    return WaitHourCount.objects.filter(hour__gte=report.since, hour__lt=report.until)


def wait_totals(report: ReportFilter) -> tuple[int, float]:
    """How many waits the fleet had in the range and their seconds."""
    totals = _hour_rows(report).aggregate(n=Sum("count"), s=Sum("seconds"))
    return totals["n"] or 0, totals["s"] or 0.0


def waits_by_hour_of_day(report: ReportFilter) -> list[WaitStats]:
    """The fleet's waits per hour of the day (0–23, local time) over the range: one grouped
    query of at most 24 × buckets rows."""
    rows = (
        _hour_rows(report)
        .annotate(local_hour=ExtractHour("hour", tzinfo=timezone.get_current_timezone()))
        .values("local_hour", "bucket")
        .annotate(n=Sum("count"), s=Sum("seconds"))
        .order_by()
    )
    cells: list[list[tuple[int, int, float]]] = [[] for _ in range(24)]
    for row in rows:
        cells[row["local_hour"]].append((row["bucket"], row["n"], row["s"]))
    return [_stats(f"{hour:02d}:00", cells[hour]) for hour in range(24)]


def mean_wait_series(report: ReportFilter) -> list[tuple[str, float]]:
    """(label, mean wait in seconds) per hour for ranges up to three days, else per day; zero
    where nobody waited. One grouped query of at most 72 or 93 rows."""
    zone = timezone.get_current_timezone()
    if (report.end - report.start).days < 3:
        rows = _hour_rows(report).values("hour").annotate(n=Sum("count"), s=Sum("seconds"))
        means = {timezone.localtime(r["hour"]): r["s"] / r["n"] for r in rows.order_by() if r["n"]}
        series, hour = [], timezone.localtime(report.since)
        while hour < report.until:
            series.append((f"{hour:%d.%m. %H}h", means.get(hour, 0.0)))
            hour += timedelta(hours=1)
        return series
    days = (
        _hour_rows(report)
        .annotate(local_day=TruncDate("hour", tzinfo=zone))
        .values("local_day")
        .annotate(n=Sum("count"), s=Sum("seconds"))
        .order_by()
    )
    by_day = {r["local_day"]: r["s"] / r["n"] for r in days if r["n"]}
    span = (report.end - report.start).days + 1
    return [
        (f"{day:%d.%m.}", by_day.get(day, 0.0))
        for day in (report.start + timedelta(days=i) for i in range(span))
    ]


def waits_by_vehicle(report: ReportFilter) -> list[WaitStats]:
    """Each vehicle's waits over the range, the longest total first."""
    rows: QuerySet[WaitDayCount] = WaitDayCount.objects.filter(
        day__gte=report.start, day__lte=report.end
    )
    if report.vehicle_ids:
        rows = rows.filter(vehicle__in=report.vehicle_ids)
    grouped: dict[int, list[tuple[int, int, float]]] = {}
    for row in (
        rows.values("vehicle", "bucket").annotate(n=Sum("count"), s=Sum("seconds")).order_by()
    ):
        grouped.setdefault(row["vehicle"], []).append((row["bucket"], row["n"], row["s"]))
    names = _vehicle_names(set(grouped))
    stats = [_stats(names.get(pk, str(pk)), cells) for pk, cells in grouped.items()]
    return sorted(stats, key=lambda s: (-s.seconds, s.label))


@dataclass(frozen=True)
class NodeHeat:
    node_id: str
    x: float
    y: float
    count: int
    seconds: float


@dataclass(frozen=True)
class WaitHeatmap:
    """Wait seconds per node of one layout, with the layout's nodes and edges to draw under it."""

    map_id: str
    nodes: list[tuple[float, float]]
    edges: list[tuple[float, float, float, float]]
    heat: list[NodeHeat]
    maps: list[str]  # every map with waits in the range (to choose another)


def wait_heatmap(report: ReportFilter, *, map_id: str = "") -> WaitHeatmap | None:
    """Wait seconds per node over the range on `map_id` (default: the map with the most)."""
    rows = WaitNodeDay.objects.filter(day__gte=report.start, day__lte=report.end)
    if report.vehicle_ids:
        rows = rows.filter(vehicle__in=report.vehicle_ids)
    else:
        rows = rows.filter(vehicle__isnull=True)  # the fleet's rows
    totals = list(
        rows.values("map_id", "node_id").annotate(n=Sum("count"), s=Sum("seconds")).order_by()
    )
    per_map: dict[str, float] = {}
    for row in totals:
        per_map[row["map_id"]] = per_map.get(row["map_id"], 0.0) + row["s"]
    if not per_map:
        return None
    chosen = map_id if map_id in per_map else max(per_map, key=lambda m: per_map[m])
    layout = Map.objects.filter(map_id=chosen).first()
    places = (
        {n: (x, y) for n, x, y in Node.objects.filter(map=layout).values_list("node_id", "x", "y")}
        if layout
        else {}
    )
    edges = (
        list(
            Edge.objects.filter(map=layout).values_list("start__x", "start__y", "end__x", "end__y")
        )
        if layout
        else []
    )
    heat = [
        NodeHeat(row["node_id"], *places[row["node_id"]], row["n"], row["s"])
        for row in totals
        if row["map_id"] == chosen and row["node_id"] in places
    ]
    return WaitHeatmap(chosen, list(places.values()), edges, heat, sorted(per_map))
