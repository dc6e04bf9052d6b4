"""Property: on random small layouts, random tasks and random delays never deadlock or collide.

Layouts are well-formed: an open grid core (a few random obstacles, kept connected) with
workstations on spurs above it and parking spurs below it, one parking spur per vehicle at
least. The executor releases steps through the ADG only; after every event the test checks that
no two vehicles hold conflicting released resources, and at the end that every task finished.
"""

from collections import deque

from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from tests.traffic.helpers import ListTasks, manager
from tests.traffic.test_adg import released_conflicts
from traffic.des import SimConfig, SimStats, Simulation
from traffic.layout import Layout
from traffic.plans import Goal


def connected(free: set[tuple[int, int]]) -> bool:
    start = next(iter(free))
    seen, todo = {start}, deque([start])
    while todo:
        r, c = todo.popleft()
        for cell in ((r + 1, c), (r - 1, c), (r, c + 1), (r, c - 1)):
            if cell in free and cell not in seen:
                seen.add(cell)
                todo.append(cell)
    return len(seen) == len(free)


@st.composite
def scenarios(draw: st.DrawFn) -> tuple[Layout, dict[str, str], dict[str, list[list[Goal]]]]:
    rows, cols = draw(st.integers(3, 5)), draw(st.integers(3, 6))
    core = {(r, c) for r in range(1, rows + 1) for c in range(cols)}
    for cell in draw(st.lists(st.sampled_from(sorted(core)), max_size=3)):
        if 1 < cell[0] < rows and connected(core - {cell}):
            core.discard(cell)  # inner obstacles only: spurs stay attached
    stations = [(0, c) for c in range(cols)]
    parking = [(rows + 1, c) for c in range(cols)]
    layout = Layout.grid(core | set(stations) | set(parking), parking=parking)
    vehicles = draw(st.integers(1, min(4, cols)))
    homes = draw(st.permutations(parking))[:vehicles]
    names = [f"v{i}" for i in range(vehicles)]
    starts = {name: f"{r},{c}" for name, (r, c) in zip(names, homes, strict=True)}
    station = st.sampled_from([f"{r},{c}" for r, c in stations])
    dwell = st.sampled_from([0.0, 3.0])
    task = st.lists(st.builds(Goal, station, dwell), min_size=1, max_size=2)
    tasks = {name: draw(st.lists(task, min_size=1, max_size=3)) for name in names}
    return layout, starts, tasks


class CheckedSimulation(Simulation):
    """Asserts the ADG safety invariant after every arrival."""

    def _arrive(self, car):  # type: ignore[no-untyped-def]
        super()._arrive(car)
        assert released_conflicts(self.manager) == []


@settings(
    max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow], derandomize=True
)
@given(
    scenarios(),
    st.integers(0, 10_000),
    st.sampled_from([0.0, 0.2, 0.5]),
)
def test_random_tasks_and_delays_never_deadlock(scenario, seed, delay_probability):  # type: ignore[no-untyped-def]
    layout, starts, tasks = scenario
    source = ListTasks(tasks)
    sim = CheckedSimulation(manager(layout, starts), source, delayed(seed, delay_probability))
    assert_all_done_safely(sim.run(3000.0), source, tasks)


def delayed(seed: int, delay_probability: float) -> SimConfig:
    """The properties' executor settings: delays of 1-15 s, stalls counted after 1,000 s."""
    return SimConfig(
        delay_probability=delay_probability,
        delay_range=(1.0, 15.0),
        seed=seed,
        stall_after=1000.0,
        check_every=5.0,
    )


def assert_all_done_safely(
    stats: SimStats, source: ListTasks, tasks: dict[str, list[list[Goal]]]
) -> None:
    """Every task finished, with no collision, wait-for cycle or stall."""
    assert source.done == {name: len(todo) for name, todo in tasks.items()}
    assert stats.collisions == 0
    assert stats.wait_cycles == 0
    assert stats.stalls == 0
