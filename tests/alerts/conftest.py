"""Fixtures: the in-process controller + simulator harness on a fake monotonic clock."""

import time
from collections.abc import Callable
from types import SimpleNamespace

import pytest

from alerts.services import observe as alert_observe
from inventory.services import observe as inventory_observe
from maps.models import Map
from orders.services import floor
from tests.alerts.harness import Clock, Harness


@pytest.fixture
def clock(monkeypatch: pytest.MonkeyPatch) -> Clock:
    fake = Clock()
    fake_time = SimpleNamespace(
        monotonic=fake, time=time.time, perf_counter=time.perf_counter, sleep=time.sleep
    )
    for module in ("control.live", "control.controller", "control.periodic"):
        monkeypatch.setattr(f"{module}.time", fake_time)
    monkeypatch.setattr(alert_observe, "_observer", alert_observe.SnapshotObserver(clock=fake))
    monkeypatch.setattr(inventory_observe, "_observer", inventory_observe.LoadObserver(clock=fake))
    monkeypatch.setattr(floor, "_late_checked_at", [float("-inf")])
    monkeypatch.setattr(floor, "LATE_CHECK_SECONDS", floor.LATE_CHECK_SECONDS)
    return fake


@pytest.fixture
def make_harness(demo_map: Map, clock: Clock) -> Callable[..., Harness]:
    def make(**kwargs: object) -> Harness:
        return Harness(layout=demo_map, clock=clock, **kwargs)  # type: ignore[arg-type]

    return make
