"""Route searches that let the controller's lock go (docs/LOAD.md, seventh round).

The manager runs the compiled search loop inside `TrafficManager.unlocked()`, checks the path
against the table once it is back, and searches again, held, when something it relied on
changed. `control.traffic_link` lets the lock go only for an order's start and the tick's
re-plans, never inside a composite change such as blocking a vehicle in error.
"""

import threading
import time
from collections.abc import Iterator
from contextlib import contextmanager
from typing import Any

import pytest
from hypothesis import example, given, settings
from hypothesis import strategies as st

from control.execution import OrderExecution
from control.live import LiveVehicle
from control.traffic_link import TrafficLink
from tests.traffic.helpers import manager
from tests.traffic.test_link import LAYOUTS, Rig, state
from tests.traffic.test_sipp import overlaps
from traffic import speedups
from traffic.layout import Layout
from traffic.manager import TrafficManager
from traffic.reservations import Hold, ReservationTable

pytestmark = pytest.mark.skipif(
    speedups.COMPILED is None, reason="only the compiled search runs unlocked"
)

CROSS = Layout.grid([(1, c) for c in range(5)] + [(r, 2) for r in (0, 2, 3, 4)])


def test_a_path_the_table_no_longer_admits_is_searched_again_held() -> None:
    m = manager(CROSS, {"a": "1,0", "b": "4,2"})

    @contextmanager
    def meanwhile() -> Iterator[None]:
        yield  # a's path is found here; then, before a commits, b plans across the middle
        m.unlocked = None
        m.plan("b", "0,2", 0.0)
        m.unlocked = meanwhile

    m.unlocked = meanwhile
    m.plan("a", "1,4", 0.0)

    assert m.searches_repeated == 1
    assert overlaps(m) == []
    alone = manager(CROSS, {"a": "1,0", "b": "4,2"}).plan("a", "1,4", 0.0)
    assert m.release_of("a").base_end < len(alone.nodes) - 1  # it now waits for b's crossing


def test_a_path_still_admitted_is_kept_without_a_second_search() -> None:
    m = manager(CROSS, {"a": "1,0", "b": "4,2"})
    alone = manager(CROSS, {"a": "1,0", "b": "4,2"})

    @contextmanager
    def meanwhile() -> Iterator[None]:
        yield
        m.on_progress("b", 0, 0.0)  # nothing that touches a's path

    m.unlocked = meanwhile
    plan = m.plan("a", "1,4", 0.0)

    held = alone.plan("a", "1,4", 0.0)
    assert m.searches_repeated == 0
    assert (plan.nodes, plan.arrive) == (held.nodes, held.arrive)


class LockedRig(Rig):
    """The link as the controller builds it, with its lock; `free` records, for each search
    that let the lock go, whether another thread could take the lock meanwhile."""

    def __init__(self, *starts: tuple[str, str]) -> None:
        self.lock = threading.RLock()
        self.vehicles = {s: LiveVehicle("sim", s, "uagv") for s, _ in starts}
        self.link = TrafficLink(lambda: self.vehicles.values(), lock=self.lock)
        self.link.ensure(LAYOUTS)
        for serial, node in starts:
            self.report(serial, state(serial, node))
        self.free: list[bool] = []
        let_go: Any = self.manager().unlocked

        @contextmanager
        def probe() -> Iterator[None]:
            with let_go():
                self.free.append(_taken_elsewhere(self.lock))
                yield

        self.manager().unlocked = probe

    def manager(self) -> TrafficManager:
        return self.link.managers["m"]


def _taken_elsewhere(lock: Any) -> bool:
    taken: list[bool] = []

    def take() -> None:
        got = lock.acquire(timeout=1.0)
        taken.append(got)
        if got:
            lock.release()

    thread = threading.Thread(target=take)
    thread.start()
    thread.join()
    return taken[0]


def test_an_order_start_lets_the_lock_go_while_its_route_is_searched() -> None:
    rig = LockedRig(("A", "W2"))
    with rig.lock:
        rig.start("A", ["W2", "W1", "C", "E1", "E2"], "W1")
    assert rig.free
    assert all(rig.free)
    assert rig.link.controls(rig.vehicles["A"], "O-A")


def test_the_tick_lets_the_lock_go_for_its_re_plans() -> None:
    rig = LockedRig(("A", "W2"), ("B", "N2"))
    with rig.lock:
        rig.start("A", ["W2", "W1", "C", "E1", "E2"], "W1")
        rig.start("B", ["N2", "N1", "C", "S1", "S2"], "N1")
        rig.report("B", state("B", "N1", order_id="O-B", seq=2))  # waits for A at N1
    rig.free.clear()
    rig.manager().replan_after = 0.0
    with rig.lock:
        rig.link.tick(time.monotonic())
    assert rig.free
    assert all(rig.free)


def test_blocking_a_vehicle_in_error_re_plans_the_others_holding_the_lock() -> None:
    rig = LockedRig(("A", "W2"), ("B", "N2"))
    with rig.lock:
        rig.start("A", ["W2", "W1", "C", "E1", "E2"], "W1")
        rig.start("B", ["N2", "N1", "C", "S1", "S2"], "N1")
    rig.free.clear()
    with rig.lock:
        rig.report("A", state("A", "W2", order_id="O-A", fatal=True))
    assert rig.free  # B was re-planned ...
    assert not any(rig.free)  # ... and nobody got the lock meanwhile


def test_a_second_start_of_a_vehicle_being_planned_waits() -> None:
    rig = LockedRig(("A", "W2"))
    second: list[object] = []
    manager = rig.manager()
    let_go: Any = manager.unlocked

    @contextmanager
    def and_start_again() -> Iterator[None]:
        with let_go():
            # the command thread and the sync both start orders: the same vehicle again
            execution = _execution("A")
            with rig.lock:
                second.append(rig.link.first_window(rig.vehicles["A"], execution, "m", None))
            yield

    manager.unlocked = and_start_again
    with rig.lock:
        rig.start("A", ["W2", "W1", "C", "E1", "E2"], "W1")
    assert second == [None]
    assert rig.link.controls(rig.vehicles["A"], "O-A")


def _execution(serial: str) -> OrderExecution:
    return OrderExecution.plan(
        transport_order_id=2, vda_order_id=f"O2-{serial}", route=["W2", "W1", "C"], pickup="W1"
    )


@settings(max_examples=300, deadline=None)
@given(
    holds=st.lists(
        st.tuples(
            st.integers(0, 3),  # vehicle
            st.floats(0, 50),  # start
            st.floats(0, 20),  # length
            st.booleans(),  # released
        ),
        max_size=8,
    ),
    start=st.floats(0, 60),
    length=st.floats(0, 20),
)
@example(holds=[(1, 0.0, 1.0, False), (1, 1.0, 0.5, False)], start=1.0, length=0.0)  # a seam
def test_admits_is_lying_inside_a_safe_interval(holds, start, length) -> None:
    table = ReservationTable(1)
    for vehicle, begin, span, released in holds:
        hold = Hold(vehicle, 0, 0, begin, begin + span, (0,))
        (table.add_released if released else table.add)(hold)
    end = start + length
    inside = any(a <= start and end <= b for a, b in table.safe_intervals(0, 0))
    assert table.admits(0, 0, start, end) == inside


def test_the_table_clock_tells_which_lists_changed() -> None:
    table = ReservationTable(3)
    since = table.clock
    table.add(Hold(1, 0, 0, 0.0, 5.0, (0, 1)))
    assert table.changed_since(0, since)
    assert table.changed_since(1, since)
    assert not table.changed_since(2, since)
