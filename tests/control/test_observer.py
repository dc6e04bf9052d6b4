"""Floor observation off control's main loop (issue 11): a flush hands its snapshots to the
observer thread, which coalesces them per vehicle and raises the alerts there."""

import threading
import time
from collections.abc import Callable, Mapping, Sequence
from typing import Any

import pytest

from alerts.models import Alert
from control.controller import Controller
from control.observer import SnapshotObserver
from control.persistence import DjangoStore, observe_floor
from robots.models import Vehicle
from tests.control.fakes import state


def test_pending_snapshots_are_coalesced_to_the_newest_per_vehicle() -> None:
    seen: list[list[Mapping[str, Any]]] = []
    observer = SnapshotObserver(lambda snapshots: seen.append(list(snapshots)))

    observer.submit([{"pk": 1, "x": 1.0}, {"pk": 2, "x": 5.0}])
    observer.submit([{"pk": 1, "x": 2.0}])
    observer.submit([])
    assert observer.run_pending() is True
    assert observer.run_pending() is False  # nothing left

    assert seen == [[{"pk": 1, "x": 2.0}, {"pk": 2, "x": 5.0}]]
    assert observer.coalesced == 1
    assert observer.idle.is_set()


def test_a_flush_without_rows_still_runs_one_pass() -> None:
    """The late-order and inventory checks run after every flush, with or without rows."""
    seen: list[int] = []
    observer = SnapshotObserver(lambda snapshots: seen.append(len(snapshots)))
    observer.submit([])
    assert observer.run_pending() is True
    assert seen == [0]


def test_a_failing_observation_does_not_stop_the_thread() -> None:
    calls: list[int] = []

    def observe(snapshots: Sequence[Mapping[str, Any]]) -> None:
        calls.append(len(snapshots))
        if len(calls) == 1:
            raise RuntimeError("database gone")

    observer = SnapshotObserver(observe)
    observer.start()
    try:
        observer.submit([{"pk": 1}])
        assert _wait(lambda: len(calls) == 1)
        observer.submit([{"pk": 1}, {"pk": 2}])
        assert _wait(lambda: calls == [1, 2])
    finally:
        observer.stop()


@pytest.mark.django_db(transaction=True)  # the observer thread has its own connection
def test_the_flush_returns_before_the_alerts_and_the_observer_raises_them() -> None:
    vehicle = Vehicle.objects.create(
        manufacturer="sim", serial_number="AGV-1", connection=Vehicle.Connection.ONLINE
    )
    release = threading.Event()

    def observe(snapshots: Sequence[Mapping[str, Any]]) -> None:
        release.wait(10)  # a slow alert pass (e.g. a fleet-wide flood)
        observe_floor(snapshots)

    observer = SnapshotObserver(observe)
    observer.start()
    try:
        controller = Controller(
            store=DjangoStore(observer=observer), interface_name="uagv", publish=lambda *a: None
        )
        controller.load()
        controller.handle_message(
            "uagv/v2/sim/AGV-1/state", state(errors=(("motorFault", "FATAL", ""),))
        )
        controller.flush()  # does not wait for the observation
        vehicle.refresh_from_db()
        assert vehicle.last_node_id == "a"  # the snapshot is saved
        assert not Alert.objects.exists()

        release.set()
        assert observer.wait_idle(10)
        alert = Alert.objects.get()
        assert alert.cause == f"vda:{vehicle.pk}:motorFault"
        assert alert.severity == "FATAL"
    finally:
        release.set()
        observer.stop()


def _wait(condition: Callable[[], bool], timeout: float = 5.0) -> bool:
    done = threading.Event()
    for _ in range(int(timeout / 0.02)):
        if condition():
            return True
        done.wait(0.02)
    return condition()


def test_passes_are_at_least_the_minimum_interval_apart_and_coalesce_meanwhile() -> None:
    passes: list[tuple[float, list[float]]] = []
    observer = SnapshotObserver(
        lambda snapshots: passes.append((time.monotonic(), [s["x"] for s in snapshots])),
        min_interval=0.4,
    )
    observer.start()
    try:
        observer.submit([{"pk": 1, "x": 1.0}])
        deadline = time.monotonic() + 5
        while not passes and time.monotonic() < deadline:
            time.sleep(0.01)
        for x in (2.0, 3.0, 4.0):  # three flushes while the observer rests
            observer.submit([{"pk": 1, "x": x}])
            time.sleep(0.05)
        while len(passes) < 2 and time.monotonic() < deadline:
            time.sleep(0.01)
    finally:
        observer.stop()
    assert [xs for _, xs in passes] == [[1.0], [4.0]]
    assert passes[1][0] - passes[0][0] >= 0.4
