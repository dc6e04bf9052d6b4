"""Switching (`traffic.switching`): a waiting vehicle goes ahead of a late one, safely.

The release guarantee rests on the stored plan times being a consistent schedule for the
queues (`schedule_breaks` below finds every pair that is not); the tests check it after every
event of delayed runs with switching on, and that such runs never collide, never wait in a
cycle and finish every task.
"""

import random

from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from bench.traffic.fleet import WarehouseTasks, fleet_manager, node_id
from bench.traffic.maps import warehouse
from tests.traffic.helpers import ListTasks, manager
from tests.traffic.test_adg import released_conflicts
from tests.traffic.test_deadlock_property import assert_all_done_safely, delayed, scenarios
from traffic.des import SimConfig, Simulation
from traffic.layout import Layout
from traffic.manager import TrafficManager
from traffic.plans import Release, ReleasePolicy

EPS = 1e-6
# a lane (row 0) with a bay below each end: a drives the lane east, b comes the other way
LANE = Layout.grid([(0, c) for c in range(9)] + [(1, 2), (1, 6)], parking=[(1, 2), (1, 6)])


def schedule_breaks(m: TrafficManager) -> list[tuple[object, object]]:
    """Pairs of conflicting holds of different vehicles whose queue order disagrees with
    their plan times, or which overlap (the invariant the ADG argument needs)."""
    found: list[tuple[object, object]] = []
    for r, queue in enumerate(m.table.blocked):
        for pos, a in enumerate(queue):
            if a.resource != r:
                continue  # each pair once, from the list of a's own resource
            for other_pos, b in enumerate(queue):
                if b.vehicle == a.vehicle:
                    continue
                ahead_late = other_pos < pos and not a.released and b.end > a.start + EPS
                behind_early = other_pos > pos and (b.released or a.end > b.start + EPS)
                if ahead_late or behind_early:
                    found.append((a, b))
    return found


def head_on(**options: object) -> TrafficManager:
    """a (planned first) drives the lane east from 0,0; b waits in the east bay to drive the
    lane west into the west bay, behind a."""
    policy = ReleasePolicy(max_steps=1, max_distance=1.0)
    m = manager(LANE, {"a": "0,0", "b": "1,6"}, policy=policy, **options)
    m.plan("a", "0,8", 0.0)
    m.plan("b", "1,2", 0.0)
    return m


def test_a_vehicle_waiting_behind_a_late_one_goes_first_when_switching() -> None:
    m = head_on(switching=True, switch_push=30.0)
    assert m.waiting_for("b") == ["a"]
    for now in (10.0, 11.0):  # a has not reached 0,1 in 10 s (stuck in a delay)
        m.tick(now)
    assert m.switches == 1
    assert m.switch_pushes == 1  # a's plan was pushed back behind b's stretch
    assert m.release_of("b").base_end == 1  # b drives into the lane
    b, a = m.vehicle("b"), m.vehicle("a")
    assert b.arrive[-1] <= a.depart[1]  # b is through before a leaves 0,1
    assert schedule_breaks(m) == []
    m.on_progress("a", 1, 11.5)  # a arrives at 0,1 and waits there for b
    assert m.waiting_for("a") == ["b"]
    for i in range(1, 6):  # b drives the lane to 0,2
        m.on_progress("b", i, 12.0 + i)
        assert released_conflicts(m) == []
        assert schedule_breaks(m) == []
        assert m.waiting_for("a") == ["b"]
    m.on_progress("b", 6, 19.0)  # b is in the west bay: a may go on
    assert m.waiting_for("a") == []
    assert m.release_of("a").base_end == 2


def test_without_switching_the_vehicle_waits_for_the_late_one() -> None:
    m = head_on()
    for now in (10.0, 11.0):
        m.tick(now)
    assert m.switches == 0
    assert m.release_of("b").base_end == 0
    assert m.waiting_for("b") == ["a"]


def test_no_switch_when_the_late_vehicle_would_be_pushed_too_far() -> None:
    m = head_on(switching=True, switch_push=2.0)
    for now in (10.0, 11.0):
        m.tick(now)
    assert m.switches == 0
    assert m.waiting_for("b") == ["a"]


def test_no_switch_ahead_of_a_vehicle_that_is_there_already() -> None:
    policy = ReleasePolicy(max_steps=8, max_distance=8.0)  # a's base covers the whole lane
    m = manager(LANE, {"a": "0,0", "b": "1,6"}, policy=policy, switching=True, switch_push=30.0)
    m.plan("a", "0,8", 0.0)
    m.plan("b", "1,2", 0.0)
    for now in (10.0, 11.0):
        m.tick(now)
    assert m.switches == 0
    assert m.waiting_for("b") == ["a"]


class ScheduleChecked(Simulation):
    """Checks the ADG invariants after every arrival (released holds never conflict; plan
    times are a consistent schedule for the queues)."""

    def _arrive(self, car):  # type: ignore[no-untyped-def]
        super()._arrive(car)
        assert released_conflicts(self.manager) == []
        assert schedule_breaks(self.manager) == []

    def _tick(self) -> None:
        super()._tick()
        assert schedule_breaks(self.manager) == []


def small_warehouse(seed: int, vehicles: int = 8) -> tuple[TrafficManager, WarehouseTasks]:
    """S1's pattern shrunk to 28 x 15 (1-cell aisles, workstations in the margins), with
    switching on: 8 vehicles there switch a dozen times in 600 s."""
    grid = warehouse(block_cols=3, block_rows=4, block_len=6, margin=3, station_cols=1)
    layout = Layout.grid(grid.free, parking=grid.stations)
    chosen = random.Random(seed).sample(sorted(grid.stations), vehicles)
    starts = [(node_id(cell), 0.0) for cell in chosen]
    m = fleet_manager(
        layout,
        starts,
        policy=ReleasePolicy(4, 4.0, 1.0),
        max_expansions=20_000,
        quick_search=(1_000, 2.0),
        switch_push=10.0,
    )
    tasks = WarehouseTasks(grid, seed, m.vehicle_ids)
    tasks.standing({f"v{i}": node for i, (node, _) in enumerate(starts)})
    return m, tasks


def test_a_delayed_warehouse_run_switches_and_keeps_the_schedule_consistent() -> None:
    m, tasks = small_warehouse(seed=0)
    config = SimConfig(seed=0, retry_backoff=2.0, reassign_after=3)  # 5 % of moves +5-30 s
    stats = ScheduleChecked(m, tasks, config).run(600.0)
    assert len(stats.tasks) > 30
    assert (stats.collisions, stats.wait_cycles, stats.stalls) == (0, 0, 0)
    assert m.switches > 5
    assert m.switch_pushes > 0


def test_state_messages_leave_switches_to_the_next_tick() -> None:
    """A switch that pushes re-times other vehicles (milliseconds on a busy layout): no state
    message makes one; the waiting vehicle switches at the next tick instead."""
    m, tasks = small_warehouse(seed=0)
    on_progress, switched_on_progress = m.on_progress, []

    def counted(vehicle_id: str, passed: int, now: float) -> list[Release]:
        before = m.switches, m.switch_pushes
        releases = on_progress(vehicle_id, passed, now)
        switched_on_progress.append((m.switches, m.switch_pushes) != before)
        return releases

    m.on_progress = counted  # type: ignore[method-assign]
    config = SimConfig(seed=0, retry_backoff=2.0, reassign_after=3)
    stats = Simulation(m, tasks, config).run(600.0)
    assert (stats.collisions, stats.wait_cycles, stats.stalls) == (0, 0, 0)
    assert len(switched_on_progress) > 1000
    assert not any(switched_on_progress)
    assert m.switches > 5
    assert m.switch_pushes > 0


@settings(
    max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow], derandomize=True
)
@given(
    scenarios(),
    st.integers(0, 10_000),
    st.sampled_from([0.2, 0.5]),
    st.sampled_from([0.0, 10.0, 60.0]),
)
def test_random_delays_with_switching_never_collide_or_deadlock(  # type: ignore[no-untyped-def]
    scenario, seed, delay_probability, push
):
    layout, starts, tasks = scenario
    source = ListTasks(tasks)
    m = manager(layout, starts, switching=True, switch_push=push, policy=ReleasePolicy(4, 4.0))
    stats = ScheduleChecked(m, source, delayed(seed, delay_probability)).run(3000.0)
    assert_all_done_safely(stats, source, tasks)


@settings(
    max_examples=20, deadline=None, suppress_health_check=[HealthCheck.too_slow], derandomize=True
)
@given(
    st.integers(0, 10_000),
    st.integers(6, 12),
    st.sampled_from([0.05, 0.2, 0.4]),
    st.sampled_from([0.0, 10.0, 60.0]),
)
def test_random_delays_in_a_warehouse_with_switching_never_collide_or_deadlock(
    seed: int, vehicles: int, delay_probability: float, push: float
) -> None:
    """Random fleets, delays and push limits in the small warehouse, the schedule checked
    after every event. (The small layouts above seldom switch; here every one of the 20
    examples switched, 1 to 12 times, when this was written.)"""
    m, tasks = small_warehouse(seed, vehicles)
    m.switch_push = push
    config = SimConfig(
        delay_probability=delay_probability, seed=seed, retry_backoff=2.0, reassign_after=3
    )
    stats = ScheduleChecked(m, tasks, config).run(400.0)
    assert len(stats.tasks) > 0
    assert (stats.collisions, stats.wait_cycles, stats.stalls) == (0, 0, 0)


def test_switching_is_off_by_default() -> None:
    m = head_on()
    assert not m.switching
