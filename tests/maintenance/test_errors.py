"""Error history from VDA 5050 errors: occurrences, counts, MTBF and top types."""

from typing import Any

import pytest

from maintenance import selectors, services
from maintenance.models import ErrorRecord, VehicleCounters
from maintenance.services.observe import CounterObserver
from tests.factories import VehicleFactory


def state(vehicle: Any, *errors: tuple[str, str]) -> dict[str, Any]:
    return {
        "pk": vehicle.pk,
        "connection": "ONLINE",
        "operating_mode": "AUTOMATIC",
        "errors": [{"errorType": t, "errorLevel": level} for t, level in errors],
    }


def test_each_occurrence_is_recorded_and_closed_with_counts_and_mtbf(db: None) -> None:
    vehicle = VehicleFactory()
    observer = CounterObserver()
    sequence = [
        (),
        (("laserBlocked", "WARNING"),),
        (("laserBlocked", "WARNING"),),  # the same occurrence
        (),
        (("laserBlocked", "WARNING"), ("motorFault", "FATAL")),
        (),
        (("motorFault", "FATAL"),),
    ]
    for second, errors in enumerate(sequence):
        observer.observe([state(vehicle, *errors)], now=float(second))
    VehicleCounters.objects.update_or_create(vehicle=vehicle, defaults={"operating_seconds": 36000})

    stats = selectors.error_stats(vehicle=vehicle)

    assert ErrorRecord.objects.filter(vehicle=vehicle).count() == 4
    assert (stats.total, stats.fatal, stats.open) == (4, 2, 1)
    assert stats.top_types == [("laserBlocked", 2), ("motorFault", 2)]
    assert stats.mtbf_hours == pytest.approx(5.0)
    assert stats.by_level == {"WARNING": 2, "FATAL": 2}


def test_open_errors_survive_a_restart_without_a_duplicate(db: None) -> None:
    vehicle = VehicleFactory()
    CounterObserver().observe([state(vehicle, ("x", "WARNING"))], now=0.0)
    CounterObserver().observe([state(vehicle, ("x", "WARNING"))], now=1.0)  # control restarted
    assert ErrorRecord.objects.filter(vehicle=vehicle).count() == 1


def test_the_flush_hook_never_raises(db: None, monkeypatch: pytest.MonkeyPatch) -> None:
    def broken(*args: Any, **kwargs: Any) -> None:
        raise RuntimeError("boom")

    monkeypatch.setattr(services.OBSERVER, "observe", broken)
    services.observe_snapshots(snapshots=[{"pk": 1}])  # logged, not raised
