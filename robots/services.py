"""Writes of the vehicle registry. The live snapshot is written in batches by `control`."""

from collections.abc import Iterable, Sequence
from typing import Any

from django.db import transaction

from robots.models import Vehicle

SNAPSHOT_FIELDS = [
    "connection",
    "protocol_version",
    "interface_name",
    "map_id",
    "x",
    "y",
    "theta",
    "position_initialized",
    "battery_charge",
    "charging",
    "driving",
    "paused",
    "operating_mode",
    "errors",
    "loads",
    "order_id",
    "order_update_id",
    "last_node_id",
    "last_node_sequence_id",
    "last_seen",
    "clock_skew",
    "protocol_counters",
]


def register_vehicles(*, identities: Iterable[tuple[str, str]]) -> dict[tuple[str, str], int]:
    """Create registry rows for vehicles seen for the first time; return the ids of all of them.

    Idempotent and race-free: a row another process created first is simply reused.
    """
    wanted = set(identities)
    if not wanted:
        return {}
    Vehicle.objects.bulk_create(
        [Vehicle(manufacturer=m, serial_number=s) for m, s in wanted], ignore_conflicts=True
    )
    found: dict[tuple[str, str], int] = {}
    for manufacturer in {m for m, _ in wanted}:
        serials = [s for m, s in wanted if m == manufacturer]
        for pk, serial in Vehicle.objects.filter(
            manufacturer=manufacturer, serial_number__in=serials
        ).values_list("pk", "serial_number"):
            found[(manufacturer, serial)] = pk
    return found


@transaction.atomic
def save_snapshots(*, snapshots: Sequence[dict[str, Any]]) -> int:
    """Write live snapshots (dicts with `pk` and SNAPSHOT_FIELDS) in one bulk update."""
    if not snapshots:
        return 0
    vehicles = [Vehicle(**snapshot) for snapshot in snapshots]
    return Vehicle.objects.bulk_update(vehicles, SNAPSHOT_FIELDS, batch_size=500)


def save_factsheets(*, factsheets: dict[int, dict[str, Any]]) -> None:
    """Store the latest factsheet of each vehicle (they change rarely, so one update each)."""
    for pk, factsheet in factsheets.items():
        Vehicle.objects.filter(pk=pk).update(factsheet=factsheet)
