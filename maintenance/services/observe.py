"""Counters and error history from vehicle snapshots, kept cheaply for `control`'s flush.

Operating time (online in an automatic mode), driving time, distance and charge cycles grow in
memory and are written every 30 s per vehicle as increments (so a restart loses at most that
much). VDA 5050 errors become `ErrorRecord`s when they appear and are closed when they go.

This runs on `control`'s observer thread for every flush (up to 1,000 vehicles a second), so on
PostgreSQL each kind of write is one set-based statement per batch whatever the fleet size (issue
11: per-vehicle statements were 15 % of control's CPU). The rows travel as ONE jsonb parameter:
psycopg re-parses a query with thousands of placeholders on every call. Other databases (SQLite
in the embedded demo) keep the portable per-row statements, with the same results.
"""

import json
import logging
import math
import time
from collections.abc import Collection, Mapping, Sequence
from dataclasses import dataclass, field
from datetime import datetime
from typing import Any, cast

from django.db import connection, transaction
from django.db.models import F, Field, Model
from django.utils import timezone

from maintenance.models import ErrorRecord, VehicleCounters

logger = logging.getLogger(__name__)

WRITE_EVERY = 30.0  # seconds between counter writes per vehicle
MAX_GAP = 10.0  # seconds: a longer silence between snapshots is not counted as operating
MAX_SPEED = 5.0  # m/s: a faster move is a relocalisation or a map change, not driving
WORKING_MODES = {"AUTOMATIC", "SEMIAUTOMATIC"}
COUNTERS = ("operating_seconds", "driving_seconds", "distance_m", "charge_cycles")

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
    pending: dict[str, float] = field(default_factory=lambda: dict.fromkeys(COUNTERS, 0.0))


def _errors(snap: Mapping[str, Any]) -> dict[ErrorKey, str]:
    found: dict[ErrorKey, str] = {}
    for error in snap.get("errors") or []:
        if isinstance(error, Mapping) and error.get("errorType"):
            key = (str(error["errorType"])[:200], str(error.get("errorLevel") or "WARNING")[:10])
            found[key] = str(error.get("errorDescription") or "")[:500]
    return found


class CounterObserver:
    """The per-vehicle working state of the counters; one per process.

    `set_based`: write with one statement per batch (None: when the database is PostgreSQL);
    the tests compare both ways."""

    def __init__(self, set_based: bool | None = None) -> None:
        self.tracks: dict[int, _Track] = {}
        self.set_based = set_based

    def _set_based(self) -> bool:
        return connection.vendor == "postgresql" if self.set_based is None else self.set_based

    def observe(self, snapshots: Sequence[Mapping[str, Any]], now: float | None = None) -> None:
        now = time.monotonic() if now is None else now
        wall = timezone.now()
        opened: list[ErrorRecord] = []
        closed: set[tuple[int, str, str]] = set()  # (vehicle, errorType, errorLevel)
        due: list[int] = []
        first_seen = {int(snap["pk"]) for snap in snapshots if snap.get("pk")} - self.tracks.keys()
        # What is already open in the database stays open (control restarted).
        known = self._open_errors(first_seen) if first_seen else {}
        for snap in snapshots:
            if not snap.get("pk"):
                continue
            pk = int(snap["pk"])
            errors = _errors(snap)
            track = self.tracks.get(pk)
            if track is None:
                track = self.tracks[pk] = _Track(
                    now, None, None, "", None, False, known.pop(pk, set()), written_at=now
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
            closed.update((pk, *key) for key in track.errors - errors.keys())
            track.errors = set(errors)
            if now - track.written_at >= WRITE_EVERY:
                due.append(pk)
        if opened or closed or due:
            with transaction.atomic():
                ErrorRecord.objects.bulk_create(opened)
                self._close(closed, wall)
                self.write(due, now)

    def _open_errors(self, pks: Collection[int]) -> dict[int, set[ErrorKey]]:
        """The open (errorType, errorLevel) of each vehicle of `pks`, in one query."""
        found: dict[int, set[ErrorKey]] = {}
        if self._set_based():
            rows = _select_open_errors(pks)
        else:
            ordered = sorted(pks)
            rows = [  # in chunks below the oldest SQLite limit of 999 variables
                row
                for start in range(0, len(ordered), 500)
                for row in ErrorRecord.objects.filter(
                    vehicle_id__in=ordered[start : start + 500], ended_at__isnull=True
                ).values_list("vehicle_id", "error_type", "error_level")
            ]
        for pk, error_type, level in rows:
            found.setdefault(pk, set()).add((error_type, level))
        return found

    def _close(self, closed: Collection[tuple[int, str, str]], wall: datetime) -> None:
        """End the open records of the (vehicle, errorType, errorLevel) that went away."""
        if not closed:
            return
        if self._set_based():
            _end_errors(closed, wall)
            return
        for pk, error_type, level in closed:
            ErrorRecord.objects.filter(
                vehicle_id=pk, error_type=error_type, error_level=level, ended_at__isnull=True
            ).update(ended_at=wall)

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
        """Add the pending increments of `pks` to their counters rows (created when missing)."""
        written: dict[int, _Track] = {}
        for pk in pks:
            track = self.tracks[pk]
            track.written_at = now
            if any(track.pending.values()):
                written[pk] = track  # a vehicle twice in `pks` is written once
        if not written:
            return
        increments = [(pk, track.pending) for pk, track in written.items()]
        if self._set_based():
            _add_to_counters(increments)
        else:
            for pk, pending in increments:
                VehicleCounters.objects.get_or_create(vehicle_id=pk)
                VehicleCounters.objects.filter(vehicle_id=pk).update(
                    **{name: F(name) + value for name, value in pending.items()}
                )
        for track in written.values():
            track.pending = dict.fromkeys(COUNTERS, 0.0)

    def flush_all(self) -> None:
        """Write everything pending (tests, shutdown)."""
        with transaction.atomic():
            self.write(list(self.tracks), time.monotonic())


def _select_open_errors(pks: Collection[int]) -> list[tuple[int, str, str]]:
    """PostgreSQL: the open records of all `pks`, the pks as one array parameter."""
    table, vehicle, error_type, level, ended = _names(
        ErrorRecord, "vehicle", "error_type", "error_level", "ended_at"
    )
    with connection.cursor() as cursor:
        cursor.execute(  # identifiers from the model, the values a parameter
            f"SELECT {vehicle}, {error_type}, {level} FROM {table} "  # noqa: S608
            f"WHERE {ended} IS NULL AND {vehicle} = ANY(%s::bigint[])",
            [sorted(pks)],
        )
        return [(int(pk), str(kind), str(lvl)) for pk, kind, lvl in cursor.fetchall()]


def _end_errors(closed: Collection[tuple[int, str, str]], wall: datetime) -> None:
    """PostgreSQL: one UPDATE for every (vehicle, errorType, errorLevel) that went away. The
    triples are distinct, so each open record matches at most one of them."""
    table, vehicle, error_type, level, ended = _names(
        ErrorRecord, "vehicle", "error_type", "error_level", "ended_at"
    )
    rows = [{"v": pk, "t": kind, "l": lvl} for pk, kind, lvl in closed]
    with connection.cursor() as cursor:
        cursor.execute(  # identifiers from the model, every value a parameter
            f"UPDATE {table} AS e SET {ended} = %s "  # noqa: S608
            "FROM jsonb_to_recordset(%s::jsonb) AS d(v bigint, t text, l text) "
            f"WHERE e.{vehicle} = d.v AND e.{error_type} = d.t AND e.{level} = d.l "
            f"AND e.{ended} IS NULL",
            [_field(ErrorRecord, "ended_at").get_db_prep_save(wall, connection), _json(rows)],
        )


def _add_to_counters(increments: Sequence[tuple[int, Mapping[str, float]]]) -> None:
    """PostgreSQL: add the (vehicle pk, {counter: increment}) of a batch in one upsert on the
    one-to-one `vehicle`, as `get_or_create` + `F() + value` do: a missing row starts from the
    model's defaults (`updated_at` now) plus the increments, an existing one only gains them.

    The values are finite (the codec rejects NaN and Infinity) and Python writes a float as its
    shortest round-trip form, so JSON carries them exactly and the sums are the per-row ones."""
    quote = connection.ops.quote_name
    vehicle, *counters = (_field(VehicleCounters, name) for name in ("vehicle", *COUNTERS))
    carried = [vehicle, *counters]
    defaults = [  # the other columns of a new row, as the model fills them in
        f for f in VehicleCounters._meta.concrete_fields if not f.primary_key and f not in carried
    ]
    template = VehicleCounters(vehicle_id=0)
    rows = [
        {vehicle.column: pk, **{f.column: pending[f.name] for f in counters}}
        for pk, pending in increments
    ]
    record = ", ".join(f"{quote(f.column)} {f.db_type(connection)}" for f in carried)
    columns = ", ".join(quote(f.column) for f in (*carried, *defaults))
    values = ", ".join(
        [f"d.{quote(f.column)}" for f in carried]
        + [f"%s::{f.db_type(connection)}" for f in defaults]
    )
    sums = ", ".join(f"{c} = t.{c} + EXCLUDED.{c}" for c in (quote(f.column) for f in counters))
    with connection.cursor() as cursor:
        cursor.execute(  # identifiers from the model, every value a parameter
            f"INSERT INTO {quote(VehicleCounters._meta.db_table)} AS t ({columns}) "  # noqa: S608
            f"SELECT {values} FROM jsonb_to_recordset(%s::jsonb) AS d({record}) "
            f"ON CONFLICT ({quote(vehicle.column)}) DO UPDATE SET {sums}",
            [
                *(f.get_db_prep_save(f.pre_save(template, add=True), connection) for f in defaults),
                _json(rows),
            ],
        )


def _field(model: type[Model], name: str) -> "Field[Any, Any]":
    return cast("Field[Any, Any]", model._meta.get_field(name))


def _names(model: type[Model], *fields: str) -> list[str]:
    """The quoted table name of `model` and column names of its `fields`."""
    quote = connection.ops.quote_name
    return [quote(model._meta.db_table), *(quote(_field(model, f).column) for f in fields)]


def _json(rows: list[dict[str, Any]]) -> str:
    return json.dumps(rows, separators=(",", ":"))


OBSERVER = CounterObserver()


def observe_snapshots(*, snapshots: Sequence[Mapping[str, Any]]) -> None:
    """Keep counters and error history from a batch of snapshots. Never raises: the flush it is
    called from must not fail for maintenance bookkeeping."""
    try:
        OBSERVER.observe(snapshots)
    except Exception:
        logger.exception("maintenance observation failed; skipped this batch")
