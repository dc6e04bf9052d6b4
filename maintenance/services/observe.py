"""Counters and error history from vehicle snapshots, kept cheaply for `control`'s flush.

Operating time (online in an automatic mode), driving time, distance and charge cycles grow in
memory and are written every 30 s per vehicle as increments (so a restart loses at most that
much). VDA 5050 errors become `ErrorRecord`s when they appear and are closed when they go.
"""

import logging
import math
import time
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

from django.db import transaction
from django.db.models import F
from django.utils import timezone

from maintenance.models import ErrorRecord, VehicleCounters

logger = logging.getLogger(__name__)

WRITE_EVERY = 30.0  # seconds between counter writes per vehicle
MAX_GAP = 10.0  # seconds: a longer silence between snapshots is not counted as operating
MAX_SPEED = 5.0  # m/s: a faster move is a relocalisation or a map change, not driving
WORKING_MODES = {"AUTOMATIC", "SEMIAUTOMATIC"}

ErrorKey = tuple[str, str]  # (errorType, errorLevel)


@dataclass
class _Track:
    at: float
    x: float | None
    y: float | None
    map_id: str
    charge: float | None
    charging: bool
    errors: set[ErrorKey]
    written_at: float
    pending: dict[str, float] = field(
        default_factory=lambda: dict.fromkeys(
            ("operating_seconds", "driving_seconds", "distance_m", "charge_cycles"), 0.0
        )
    )


def _errors(snap: Mapping[str, Any]) -> dict[ErrorKey, str]:
    found: dict[ErrorKey, str] = {}
    for error in snap.get("errors") or []:
        if isinstance(error, Mapping) and error.get("errorType"):
            key = (str(error["errorType"])[:200], str(error.get("errorLevel") or "WARNING")[:10])
            found[key] = str(error.get("errorDescription") or "")[:500]
    return found


class CounterObserver:
    """The per-vehicle working state of the counters; one per process."""

    def __init__(self) -> None:
        self.tracks: dict[int, _Track] = {}

    def observe(self, snapshots: Sequence[Mapping[str, Any]], now: float | None = None) -> None:
        now = time.monotonic() if now is None else now
        wall = timezone.now()
        opened: list[ErrorRecord] = []
        closed: dict[int, set[ErrorKey]] = {}
        due: list[int] = []
        for snap in snapshots:
            if not snap.get("pk"):
                continue
            pk = int(snap["pk"])
            errors = _errors(snap)
            track = self.tracks.get(pk)
            if track is None:
                # What is already open in the database stays open (control restarted).
                known = set(
                    ErrorRecord.objects.filter(vehicle_id=pk, ended_at__isnull=True).values_list(
                        "error_type", "error_level"
                    )
                )
                track = self.tracks[pk] = _Track(
                    now, None, None, "", None, False, known, written_at=now
                )
            self._count(track, snap, now)
            for key in errors.keys() - track.errors:
                opened.append(
                    ErrorRecord(
                        vehicle_id=pk,
                        error_type=key[0],
                        error_level=key[1],
                        description=errors[key],
                        started_at=wall,
                    )
                )
            if track.errors - errors.keys():
                closed[pk] = track.errors - errors.keys()
            track.errors = set(errors)
            if now - track.written_at >= WRITE_EVERY:
                due.append(pk)
        if opened or closed or due:
            with transaction.atomic():
                ErrorRecord.objects.bulk_create(opened)
                for pk, keys in closed.items():
                    for error_type, level in keys:
                        ErrorRecord.objects.filter(
                            vehicle_id=pk,
                            error_type=error_type,
                            error_level=level,
                            ended_at__isnull=True,
                        ).update(ended_at=wall)
                self.write(due, now)

    def _count(self, track: _Track, snap: Mapping[str, Any], now: float) -> None:
        seconds = now - track.at
        x, y, map_id = snap.get("x"), snap.get("y"), str(snap.get("map_id") or "")
        if 0 < seconds <= MAX_GAP:
            working = snap.get("connection") == "ONLINE" and snap.get("operating_mode") in (
                WORKING_MODES
            )
            if working:
                track.pending["operating_seconds"] += seconds
            if snap.get("driving"):
                track.pending["driving_seconds"] += seconds
        if None not in (x, y, track.x, track.y) and map_id == track.map_id:
            metres = math.dist((x, y), (track.x, track.y))  # type: ignore[arg-type]
            if metres <= MAX_SPEED * max(seconds, 1.0) and seconds <= MAX_GAP:
                track.pending["distance_m"] += metres
        charge, charging = snap.get("battery_charge"), bool(snap.get("charging"))
        if charge is not None and track.charge is not None and (charging or track.charging):
            track.pending["charge_cycles"] += max(0.0, float(charge) - track.charge) / 100.0
        track.at, track.x, track.y, track.map_id = now, x, y, map_id
        track.charge = None if charge is None else float(charge)
        track.charging = charging

    def write(self, pks: Sequence[int], now: float) -> None:
        """Add the pending increments of `pks` to their counters rows."""
        for pk in pks:
            track = self.tracks[pk]
            pending = track.pending
            track.written_at = now
            if not any(pending.values()):
                continue
            VehicleCounters.objects.get_or_create(vehicle_id=pk)
            VehicleCounters.objects.filter(vehicle_id=pk).update(
                **{name: F(name) + value for name, value in pending.items()}
            )
            track.pending = dict.fromkeys(pending, 0.0)

    def flush_all(self) -> None:
        """Write everything pending (tests, shutdown)."""
        with transaction.atomic():
            self.write(list(self.tracks), time.monotonic())


OBSERVER = CounterObserver()


def observe_snapshots(*, snapshots: Sequence[Mapping[str, Any]]) -> None:
    """Keep counters and error history from a batch of snapshots. Never raises: the flush it is
    called from must not fail for maintenance bookkeeping."""
    try:
        OBSERVER.observe(snapshots)
    except Exception:
        logger.exception("maintenance observation failed; skipped this batch")
