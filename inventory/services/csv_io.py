"""CSV import and export of storage locations and stock (all-or-nothing imports)."""

import csv
import io
from typing import Any

from django.db import transaction

from fleet.exceptions import InvalidRequestError
from inventory.models import LoadCarrier, Movement, StorageLocation
from inventory.services.stock import _place
from maps.models import Station

COLUMNS = {
    "locations": ["map_id", "station_id", "capacity", "note"],
    "stock": [
        "load_id",
        "load_type",
        "map_id",
        "station_id",
        "slot",
        "length",
        "width",
        "height",
        "weight",
    ],
}
_DIMENSIONS = ("length", "width", "height", "weight")


def export_csv(kind: str) -> str:
    """The locations or the stock as CSV text (header row first)."""
    out = io.StringIO()
    writer = csv.writer(out)
    writer.writerow(COLUMNS[_kind(kind)])
    if kind == "locations":
        for loc in StorageLocation.objects.select_related("station__map"):
            writer.writerow(
                [loc.station.map.map_id, loc.station.station_id, loc.capacity, loc.note]
            )
    else:
        for load in LoadCarrier.objects.select_related("location__station__map"):
            station = load.location.station if load.location else None
            writer.writerow(
                [
                    load.load_id,
                    load.load_type,
                    station.map.map_id if station else "",
                    station.station_id if station else "",
                    "" if load.slot is None else load.slot,
                    *("" if getattr(load, d) is None else getattr(load, d) for d in _DIMENSIONS),
                ]
            )
    return out.getvalue()


def _kind(kind: str) -> str:
    if kind not in COLUMNS:
        raise InvalidRequestError(f"unknown CSV kind {kind!r}; use locations or stock")
    return kind


def _station(row: dict[str, str], line: int) -> Station:
    station = Station.objects.filter(
        map__map_id=row.get("map_id", "").strip(), station_id=row.get("station_id", "").strip()
    ).first()
    if station is None:
        raise InvalidRequestError(
            f"line {line}: no station {row.get('station_id')!r} on map {row.get('map_id')!r}"
        )
    return station


def _number(value: str, line: int, name: str, cast: Any = float) -> Any:
    if value is None or not value.strip():
        return None
    try:
        result = cast(value)
    except ValueError:
        raise InvalidRequestError(f"line {line}: {name} {value!r} is not a number") from None
    if result < 0:
        raise InvalidRequestError(f"line {line}: {name} must not be negative")
    return result


@transaction.atomic
def import_csv(kind: str, text: str) -> int:
    """Create or update locations or stock from CSV; any bad row rejects the whole file.

    Stock rows place each load at its station (empty station: known but not stored); the
    move is recorded as an IMPORT movement. Returns the number of rows applied.
    """
    reader = csv.DictReader(io.StringIO(text))
    missing = (
        set(COLUMNS[_kind(kind)]) - {"note", *_DIMENSIONS, "slot"} - set(reader.fieldnames or [])
    )
    if missing:
        raise InvalidRequestError(f"missing columns: {', '.join(sorted(missing))}")
    count = 0
    for line, row in enumerate(reader, start=2):
        if kind == "locations":
            capacity = _number(row.get("capacity", ""), line, "capacity", int)
            if not capacity:
                raise InvalidRequestError(f"line {line}: capacity must be at least 1")
            StorageLocation.objects.update_or_create(
                station=_station(row, line),
                defaults={"capacity": capacity, "note": (row.get("note") or "")[:200]},
            )
        else:
            load_id = (row.get("load_id") or "").strip()
            if not load_id:
                raise InvalidRequestError(f"line {line}: load_id is empty")
            dims = {d: _number(row.get(d) or "", line, d) for d in _DIMENSIONS}
            load, _ = LoadCarrier.objects.update_or_create(
                load_id=load_id,
                defaults={"load_type": (row.get("load_type") or "EPAL").strip(), **dims},
            )
            location = None
            if (row.get("station_id") or "").strip():
                station = _station(row, line)
                location = StorageLocation.objects.filter(station=station).first()
                if location is None:
                    raise InvalidRequestError(
                        f"line {line}: station {station.station_id} is not a storage location"
                    )
            slot = _number(row.get("slot") or "", line, "slot", int)
            if location is not None and slot is not None and not 1 <= slot <= location.capacity:
                raise InvalidRequestError(
                    f"line {line}: slot {slot} outside 1..{location.capacity}"
                )
            _place(
                load, reason=Movement.Reason.IMPORT, location=location, vehicle_id=None, slot=slot
            )
            if location is not None and load.slot != slot:
                load.slot = slot
                load.save(update_fields=["slot"])
        count += 1
    return count
