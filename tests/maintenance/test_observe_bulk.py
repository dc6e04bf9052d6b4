"""Issue 11: on PostgreSQL the counter observer writes a batch with a constant number of
statements, and those give exactly the counters and error history of the per-row writes."""

from datetime import UTC, datetime, timedelta
from typing import Any

import pytest
from django.db import connection
from django.test.utils import CaptureQueriesContext
from django.utils import timezone

from maintenance.models import ErrorRecord, VehicleCounters
from maintenance.services.observe import CounterObserver
from tests.factories import VehicleFactory

pytestmark = pytest.mark.django_db

T0 = datetime(2026, 3, 2, 8, 0, tzinfo=UTC)


@pytest.fixture(autouse=True)
def postgresql_only() -> None:
    if connection.vendor != "postgresql":
        pytest.skip("the set-based writes are PostgreSQL statements")


def snapshot(pk: int, i: int, step: int) -> dict[str, Any] | None:
    """Vehicle number `i` at second `step`: a mix of modes, moves, jumps, charging, silences
    and errors that come and go, the same for any vehicle with the same `i`."""
    if i % 23 == 0 and 30 <= step < 45:
        return None  # silent for longer than MAX_GAP
    idle = i % 29 == 0  # never anything to count: no counters row either way
    errors = []
    if i % 3 == 0 and (step // (3 + i % 5)) % 2:
        errors.append({"errorType": "laserBlocked", "errorLevel": "WARNING"})
    if i % 4 == 0 and 10 + i % 7 <= step < 25 + i % 9:
        errors.append(
            {"errorType": "motorFault", "errorLevel": "FATAL", "errorDescription": f"m{i}"}
        )
    x = step * 0.7 * (i % 3) + (100.0 if i % 13 == 0 and step >= 20 else 0.0) + i / 7
    return {
        "pk": pk,
        "connection": "OFFLINE" if idle or (i % 11 == 0 and step > 50) else "ONLINE",
        "operating_mode": ("SEMIAUTOMATIC" if i % 7 == 0 else "AUTOMATIC") if i % 5 else "MANUAL",
        "driving": not idle and (i + step) % 4 != 0,
        "x": None if idle else x,
        "y": None if idle else i * 1.3,
        "map_id": "other" if i % 17 == 0 and step > 40 else "demo",
        "battery_charge": None if idle or i % 19 == 0 else 30 + step * 0.37 * (i % 4),
        "charging": i % 2 == 0,
        "errors": errors,
    }


def history(pk: int) -> tuple[Any, ...]:
    counters = VehicleCounters.objects.filter(vehicle_id=pk).values_list(
        "operating_seconds",
        "driving_seconds",
        "distance_m",
        "charge_cycles",
        "out_of_service",
        "out_of_service_reason",
        "updated_at",
    )
    records = ErrorRecord.objects.filter(vehicle_id=pk).values_list(
        "error_type", "error_level", "description", "started_at", "ended_at"
    )
    return tuple(counters), sorted(records, key=str)


def test_set_based_writes_give_the_per_row_counters_and_error_history(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    count = 80
    clock = [T0]
    monkeypatch.setattr(timezone, "now", lambda: clock[0])  # equal timestamps both ways
    fleets = {way: [VehicleFactory.create().pk for _ in range(count)] for way in ("set", "row")}
    for pks in fleets.values():
        for i, pk in enumerate(pks):
            if i % 6 == 0:  # open before control (re)started: kept, not duplicated
                ErrorRecord.objects.create(
                    vehicle_id=pk, error_type="laserBlocked", error_level="WARNING", started_at=T0
                )
            if i % 8 == 0:  # open before the restart and gone since: closed
                ErrorRecord.objects.create(
                    vehicle_id=pk, error_type="oldFault", error_level="ERROR", started_at=T0
                )
            if i % 5 == 1:  # counters from before: added to, service state untouched
                VehicleCounters.objects.create(
                    vehicle_id=pk, operating_seconds=123.456, out_of_service=True
                )
    observers = {"set": CounterObserver(set_based=True), "row": CounterObserver(set_based=False)}

    for step in range(66):  # two writes of every vehicle (30 s, 60 s)
        clock[0] = T0 + timedelta(seconds=step)
        for way, observer in observers.items():
            snapshots = [snapshot(pk, i, step) for i, pk in enumerate(fleets[way])]
            observer.observe([s for s in snapshots if s], now=float(step))
    clock[0] = T0 + timedelta(minutes=5)
    for observer in observers.values():
        observer.flush_all()

    for set_pk, row_pk in zip(fleets["set"], fleets["row"], strict=True):
        assert history(set_pk) == history(row_pk)
    # The comparison covered every kind of row it claims to.
    rows = VehicleCounters.objects.filter(vehicle_id__in=fleets["set"])
    assert rows.count() == count - 3  # the idle vehicles (0, 29, 58) got none
    assert rows.filter(operating_seconds__gt=123.456, out_of_service=True).count() == 16
    assert rows.filter(driving_seconds__gt=0, distance_m__gt=0, charge_cycles__gt=0).exists()
    records = ErrorRecord.objects.filter(vehicle_id__in=fleets["set"])
    assert records.filter(ended_at__isnull=False).count() > count
    assert records.filter(ended_at__isnull=True).exists()
    assert records.filter(error_type="oldFault", ended_at=T0).count() == count // 8


def batch_statements(count: int) -> tuple[int, int]:
    """Statements of a first-sighting batch and of a batch where all `count` vehicles are due,
    each closing one error and opening another."""
    pks = [VehicleFactory.create().pk for _ in range(count)]
    ErrorRecord.objects.bulk_create(
        ErrorRecord(vehicle_id=pk, error_type="old", error_level="WARNING", started_at=T0)
        for pk in pks
    )
    observer = CounterObserver()

    def batch(step: int, error: str) -> list[dict[str, Any]]:
        return [
            {
                "pk": pk,
                "connection": "ONLINE",
                "operating_mode": "AUTOMATIC",
                "x": float(step),
                "y": 0.0,
                "errors": [{"errorType": error, "errorLevel": "WARNING"}],
            }
            for pk in pks
        ]

    with CaptureQueriesContext(connection) as first:
        observer.observe(batch(0, "old"), now=0.0)
    for step in range(1, 30):
        observer.observe(batch(step, "old"), now=float(step))
    with CaptureQueriesContext(connection) as due:
        observer.observe(batch(30, "new"), now=30.0)

    counters = VehicleCounters.objects.filter(vehicle_id__in=pks, operating_seconds=30.0)
    assert counters.count() == count
    assert ErrorRecord.objects.filter(vehicle_id__in=pks, error_type="old").count() == count
    assert not ErrorRecord.objects.filter(
        vehicle_id__in=pks, error_type="old", ended_at__isnull=True
    ).exists()
    assert (
        ErrorRecord.objects.filter(
            vehicle_id__in=pks, error_type="new", ended_at__isnull=True
        ).count()
        == count
    )
    return len(first), len(due)


def test_a_batch_takes_the_same_few_statements_for_200_vehicles_as_for_5() -> None:
    few = batch_statements(5)
    many = batch_statements(200)

    assert many == few
    first, due = many
    assert first == 1  # the open errors of all new vehicles
    assert due <= 5  # insert opened, close ended, add counters (+ savepoint, release)
