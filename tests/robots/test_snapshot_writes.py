"""The PostgreSQL path of `save_snapshots` (UPDATE … FROM jsonb_to_recordset) stores exactly
what Django's bulk_update stores, for every snapshot field, NULLs and JSON included."""

from datetime import UTC, datetime
from typing import Any

import pytest
from django.db import connection

from robots.models import Vehicle
from robots.services import SNAPSHOT_FIELDS, register_vehicles, save_snapshots

pytestmark = pytest.mark.django_db

FULL = {
    "connection": "ONLINE",
    "protocol_version": "3.0.0",
    "interface_name": "uagv",
    "map_id": "hall-1",
    "x": 1.25,
    "y": -2.5,
    "theta": 3.1,
    "position_initialized": True,
    "battery_charge": 55.5,
    "charging": True,
    "driving": False,
    "paused": True,
    "operating_mode": "SEMIAUTOMATIC",
    "errors": [{"errorType": "x", "errorLevel": "WARNING", "note": 'it\'s "quoted"'}],
    "loads": [{"loadId": "L1", "weight": 12.5}],
    "order_id": "TO-7",
    "order_update_id": 3,
    "last_node_id": "n'9 ü→\\",
    "last_node_sequence_id": 18,
    "last_seen": datetime(2026, 11, 22, 8, 0, 1, 250000, tzinfo=UTC),
    "clock_skew": -0.125,
    "protocol_counters": {"duplicate": 2},
}
NULLS = {
    **FULL,
    "x": None,
    "y": None,
    "theta": None,
    "battery_charge": None,
    "order_update_id": None,
    "last_node_sequence_id": None,
    "last_seen": None,
    "clock_skew": None,
    "errors": [],
    "loads": [],
}


def _stored(pk: int) -> dict[str, Any]:
    return dict(Vehicle.objects.values(*SNAPSHOT_FIELDS).get(pk=pk))


@pytest.mark.skipif(connection.vendor != "postgresql", reason="the fast path is PostgreSQL's")
def test_fast_path_stores_what_bulk_update_stores() -> None:
    ids = register_vehicles(identities=[("a", "1"), ("a", "2"), ("b", "1"), ("b", "2")])
    fast_full, fast_null, slow_full, slow_null = ids.values()
    partial = {"connection": "OFFLINE"}  # missing fields get the model defaults, as before

    assert save_snapshots(snapshots=[{**FULL, "pk": fast_full}, {**NULLS, "pk": fast_null}]) == 2
    slow = [Vehicle(pk=slow_full, **FULL), Vehicle(pk=slow_null, **NULLS)]
    Vehicle.objects.bulk_update(slow, SNAPSHOT_FIELDS)

    assert _stored(fast_full) == _stored(slow_full) == {**FULL}
    assert _stored(fast_null) == _stored(slow_null)
    save_snapshots(snapshots=[{**partial, "pk": fast_full}])
    Vehicle.objects.bulk_update([Vehicle(pk=slow_full, **partial)], SNAPSHOT_FIELDS)
    assert _stored(fast_full) == _stored(slow_full)
    assert _stored(fast_full)["connection"] == "OFFLINE"


@pytest.mark.skipif(connection.vendor != "postgresql", reason="the fast path is PostgreSQL's")
def test_fast_path_writes_many_rows_in_batches() -> None:
    ids = register_vehicles(identities=[("m", str(i)) for i in range(1203)])
    rows = [{**FULL, "pk": pk, "x": float(i)} for i, pk in enumerate(ids.values())]

    assert save_snapshots(snapshots=rows) == 1203
    stored = Vehicle.objects.filter(manufacturer="m").order_by("x").values_list("x", flat=True)
    assert list(stored) == [float(i) for i in range(1203)]
