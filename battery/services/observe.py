"""Learning from vehicle snapshots: sampled battery history, charge cycles, the consumption
model and low-battery alerts.

Called by `control`'s flush with every batch of changed snapshots (about every second), so it
keeps its working state in memory and touches the database only when a sample is due: on a
1 % change, a charging switch, or every 5 minutes per vehicle.
"""

import logging
import math
import time
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from datetime import datetime
from typing import Any

from django.db import transaction
from django.db.models import F
from django.utils import timezone

from battery.models import BatteryAlert, BatterySample, VehicleEnergy
from battery.policy import Band, Consumption, Levels
from battery.selectors import get_policy_book
from robots.models import Vehicle

logger = logging.getLogger(__name__)

SAMPLE_STEP = 1.0  # percent
SAMPLE_EVERY = 300.0  # seconds
LEARN_EVERY = 60.0  # seconds of discharge per learning step
POLICY_TTL = 60.0  # seconds the policies are cached


@dataclass
class _Track:
    """What the observer remembers of one vehicle between snapshots."""

    charge: float
    charging: bool
    at: float
    x: float | None
    y: float | None
    map_id: str
    sample_charge: float
    sample_charging: bool
    sample_at: float
    model: Consumption
    cycles: float
    band: Band | None = None
    window: list[float] = field(default_factory=lambda: [0.0, 0.0, 0.0])  # used, m, s


class EnergyObserver:
    """Keeps the per-vehicle working state; one per process (`control` has one flusher)."""

    def __init__(self) -> None:
        self.tracks: dict[int, _Track] = {}
        self._book_at = -math.inf
        self._book: Any = None
        self._levels: dict[int, Levels] = {}  # per vehicle, from `_book`

    def observe(self, snapshots: Sequence[Mapping[str, Any]], now: float | None = None) -> int:
        """Take one batch; returns how many samples were written."""
        now = time.monotonic() if now is None else now
        wall = timezone.now()
        rows = [s for s in snapshots if s.get("battery_charge") is not None and s.get("pk")]
        if not rows:
            return 0
        self._load([int(s["pk"]) for s in rows if int(s["pk"]) not in self.tracks], rows, now)
        samples: list[BatterySample] = []
        dirty: set[int] = set()
        for snap in rows:
            pk = int(snap["pk"])
            track = self.tracks[pk]
            if self._advance(track, snap, now):
                dirty.add(pk)
                samples.append(
                    BatterySample(
                        vehicle_id=pk,
                        at=wall,
                        charge=track.charge,
                        charging=track.charging,
                        drain_per_metre=track.model.per_metre,
                    )
                )
        if samples:
            self._write(samples, dirty, wall, now)
        return len(samples)

    def _load(self, new: list[int], rows: Sequence[Mapping[str, Any]], now: float) -> None:
        energy = {e.vehicle_id: e for e in VehicleEnergy.objects.filter(vehicle_id__in=new)}
        for snap in rows:
            pk = int(snap["pk"])
            if pk in self.tracks:
                continue
            row = energy.get(pk)
            charge = float(snap["battery_charge"])
            self.tracks[pk] = _Track(
                charge=charge,
                charging=bool(snap.get("charging")),
                at=now,
                x=snap.get("x"),
                y=snap.get("y"),
                map_id=str(snap.get("map_id") or ""),
                sample_charge=math.inf,  # the first reading is always sampled
                sample_charging=bool(snap.get("charging")),
                sample_at=now,
                model=Consumption(
                    per_metre=row.drain_per_metre if row else None,
                    per_hour=row.drain_per_hour if row else None,
                ),
                cycles=row.charge_cycles if row else 0.0,
            )

    def _advance(self, track: _Track, snap: Mapping[str, Any], now: float) -> bool:
        """Update the track from one snapshot; True when a sample is due."""
        charge, charging = float(snap["battery_charge"]), bool(snap.get("charging"))
        x, y, map_id = snap.get("x"), snap.get("y"), str(snap.get("map_id") or "")
        metres = 0.0
        if None not in (x, y, track.x, track.y) and map_id == track.map_id:
            metres = math.dist((x, y), (track.x, track.y))  # type: ignore[arg-type]
        seconds = max(0.0, now - track.at)
        if charging or track.charging:
            track.cycles += max(0.0, charge - track.charge) / 100.0
            track.window = [0.0, 0.0, 0.0]  # charging mixes in; start a fresh window
        else:
            window = track.window
            window[0] += track.charge - charge
            window[1] += metres
            window[2] += seconds
            if window[2] >= LEARN_EVERY:
                track.model.observe(used=window[0], metres=window[1], seconds=window[2])
                track.window = [0.0, 0.0, 0.0]
        track.charge, track.charging, track.at = charge, charging, now
        track.x, track.y, track.map_id = x, y, map_id
        due = (
            charging != track.sample_charging
            or abs(charge - track.sample_charge) >= SAMPLE_STEP
            or now - track.sample_at >= SAMPLE_EVERY
        )
        if due:
            track.sample_charge, track.sample_charging, track.sample_at = charge, charging, now
        return due

    def _write(
        self, samples: list[BatterySample], dirty: set[int], wall: datetime, now: float
    ) -> None:
        energy = []
        for pk in dirty:
            track = self.tracks[pk]
            energy.append(
                VehicleEnergy(
                    vehicle_id=pk,
                    drain_per_metre=track.model.per_metre,
                    drain_per_hour=track.model.per_hour,
                    charge_cycles=round(track.cycles, 4),
                )
            )
        with transaction.atomic():
            BatterySample.objects.bulk_create(samples)
            VehicleEnergy.objects.bulk_create(
                energy,
                update_conflicts=True,
                unique_fields=["vehicle"],
                update_fields=["drain_per_metre", "drain_per_hour", "charge_cycles", "updated_at"],
            )
            # The first stable efficiency is the health baseline.
            VehicleEnergy.objects.filter(
                vehicle_id__in=dirty, baseline_per_metre__isnull=True, drain_per_metre__isnull=False
            ).update(baseline_per_metre=F("drain_per_metre"))
            self._alerts(dirty, wall, now)

    def _alerts(self, dirty: set[int], wall: datetime, now: float) -> None:
        """Open a low or critical alert when a vehicle enters the band, resolve it on leaving."""
        if now - self._book_at > POLICY_TTL:
            self._book, self._book_at = get_policy_book(), now
            self._levels = {}
        self._resolve_levels(dirty - self._levels.keys())
        for pk in sorted(dirty & self._levels.keys()):
            track = self.tracks[pk]
            band = self._levels[pk].band(track.charge, track.model.per_hour)
            if band == track.band:
                continue
            track.band = band
            _sync_alerts(pk, band, track.charge, wall)

    def _resolve_levels(self, pks: set[int]) -> None:
        """Each vehicle's charge levels, kept as long as the policy book: a vehicle's type
        comes from its factsheet, and decoding 1,000 factsheets per pass was most of it."""
        if not pks:
            return
        if not self._book.by_type:  # one policy for all: no factsheet needed
            for pk in Vehicle.objects.filter(pk__in=pks).values_list("pk", flat=True):
                self._levels[pk] = self._book.default
            return
        vehicles = Vehicle.objects.filter(pk__in=pks).only("pk", "manufacturer", "factsheet")
        for vehicle in vehicles:
            self._levels[vehicle.pk] = self._book.for_vehicle(vehicle)


def _sync_alerts(vehicle_id: int, band: Band, charge: float, wall: datetime) -> None:
    wanted = {Band.CRITICAL: {"CRITICAL", "LOW"}, Band.NEEDS_CHARGE: {"LOW"}}.get(band, set())
    open_levels = set(
        BatteryAlert.objects.filter(vehicle_id=vehicle_id, resolved_at__isnull=True).values_list(
            "level", flat=True
        )
    )
    for level in wanted - open_levels:
        BatteryAlert.objects.create(
            vehicle_id=vehicle_id, level=level, charge=charge, raised_at=wall
        )
    gone = open_levels - wanted
    if gone:
        BatteryAlert.objects.filter(
            vehicle_id=vehicle_id, level__in=gone, resolved_at__isnull=True
        ).update(resolved_at=wall)


OBSERVER = EnergyObserver()


def observe_snapshots(*, snapshots: Sequence[Mapping[str, Any]]) -> int:
    """Learn from a batch of snapshots (see the module docstring). Never raises: the flush it
    is called from must not fail for battery bookkeeping."""
    try:
        return OBSERVER.observe(snapshots)
    except Exception:
        logger.exception("battery observation failed; skipped this batch")
        return 0
