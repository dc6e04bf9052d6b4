"""Writes of the traffic-wait report: record finished waits, and roll them up (Celery, 1/min).

`control` knows when traffic management holds a vehicle at its decision point and for whom; its
flush hands each finished wait to `record_traffic_waits` (wired by the setting
FLEET_TRAFFIC_WAIT_RECORDER, since control and reports are independent siblings). The roll-up
adds new waits to three narrow tables (fleet per hour and bucket, vehicle per day and bucket,
vehicle per day and node), so the report page never reads the raw waits.
"""

import bisect
from collections import defaultdict
from collections.abc import Iterable, Mapping
from dataclasses import dataclass, field
from datetime import date, datetime
from typing import Any

from django.db import transaction

from reports.models import (
    WAIT_BUCKETS,
    TrafficWait,
    WaitDayCount,
    WaitHourCount,
    WaitMark,
    WaitNodeDay,
)
from reports.services import day_of, hour_of


def wait_bucket(seconds: float) -> int:
    """Index of the wait histogram bucket (the last one is everything above the largest bound)."""
    return bisect.bisect_left(WAIT_BUCKETS, seconds)


@dataclass(frozen=True)
class WaitEpisode:
    """One finished wait, as the roll-up needs it."""

    vehicle_id: int
    map_id: str
    node_id: str
    started_at: datetime
    seconds: float


def record_traffic_waits(*, episodes: Iterable[Mapping[str, Any]]) -> int:
    """Store finished waits (dicts with vehicle_id, map_id, node_id, x, y, started_at, seconds,
    waited_for) in one insert; return how many. Called from control's flush."""
    rows = [
        TrafficWait(
            vehicle_id=e["vehicle_id"],
            map_id=e.get("map_id") or "",
            node_id=e.get("node_id") or "",
            x=e.get("x"),
            y=e.get("y"),
            started_at=e["started_at"],
            seconds=max(0.0, float(e["seconds"])),
            waited_for=list(e.get("waited_for") or []),
        )
        for e in episodes
    ]
    TrafficWait.objects.bulk_create(rows, batch_size=500)
    return len(rows)


@dataclass
class WaitLedger:
    """Deltas for the wait tables, collected in memory and written by `apply`."""

    hours: dict[tuple[datetime, int], list[float]] = field(
        default_factory=lambda: defaultdict(lambda: [0, 0.0])
    )
    days: dict[tuple[date, int, int], list[float]] = field(
        default_factory=lambda: defaultdict(lambda: [0, 0.0])
    )
    nodes: dict[tuple[date, int | None, str, str], list[float]] = field(
        default_factory=lambda: defaultdict(lambda: [0, 0.0])
    )

    def add(self, wait: WaitEpisode) -> None:
        bucket, day = wait_bucket(wait.seconds), day_of(wait.started_at)
        cells = [
            self.hours[(hour_of(wait.started_at), bucket)],
            self.days[(day, wait.vehicle_id, bucket)],
        ]
        if wait.node_id:
            for vehicle_id in (wait.vehicle_id, None):  # the vehicle's row and the fleet's
                cells.append(self.nodes[(day, vehicle_id, wait.map_id, wait.node_id)])
        for cell in cells:
            cell[0] += 1
            cell[1] += wait.seconds

    def apply(self) -> None:
        """Add the deltas: per table one read, one bulk update and one bulk insert."""
        _merge(WaitHourCount, self.hours, ("hour", "bucket"), "hour")
        _merge(WaitDayCount, self.days, ("day", "vehicle_id", "bucket"), "day")
        _merge(WaitNodeDay, self.nodes, ("day", "vehicle_id", "map_id", "node_id"), "day")


def _merge(
    model: Any, deltas: Mapping[tuple[Any, ...], list[float]], key: tuple[str, ...], by: str
) -> None:
    if not deltas:
        return
    firsts = {k[0] for k in deltas}
    existing = {
        tuple(getattr(row, name) for name in key): row
        for row in model.objects.filter(**{f"{by}__in": firsts})
    }
    changed, created = [], []
    for values, (count, seconds) in deltas.items():
        row = existing.get(values)
        if row is None:
            row = model(**dict(zip(key, values, strict=True)))
            created.append(row)
        else:
            changed.append(row)
        row.count += int(count)
        row.seconds += seconds
    model.objects.bulk_update(changed, ["count", "seconds"], batch_size=500)
    model.objects.bulk_create(created, batch_size=500)


def roll_up_traffic_waits() -> int:
    """Add every wait recorded since the last roll-up to the tables; return how many.

    Exactly once per wait: the watermark (the highest id read) moves in the same transaction as
    the figures, under a row lock, so an overlapping run waits and starts where this one ended.
    Ids are a safe watermark because only the active control process writes waits, in order.
    """
    with transaction.atomic():
        WaitMark.objects.get_or_create(pk=1)
        mark = WaitMark.objects.select_for_update().get(pk=1)
        rows = (
            TrafficWait.objects.filter(pk__gt=mark.last_id)
            .order_by("pk")
            .values_list("pk", "vehicle_id", "map_id", "node_id", "started_at", "seconds")
        )
        ledger, count, last = WaitLedger(), 0, mark.last_id
        for pk, vehicle_id, map_id, node_id, started_at, seconds in rows.iterator(2000):
            ledger.add(WaitEpisode(vehicle_id, map_id, node_id, started_at, seconds))
            count, last = count + 1, pk
        if not count:
            return 0
        ledger.apply()
        mark.last_id = last
        mark.save(update_fields=["last_id"])
    return count
