"""The opt-in congestion cost (`traffic.congestion`): counted from the planned flow, it only
chooses among safe paths."""

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from tests.traffic.helpers import ListTasks, cells, manager
from tests.traffic.test_deadlock_property import (
    CheckedSimulation,
    assert_all_done_safely,
    delayed,
    scenarios,
)
from traffic import sipp
from traffic.congestion import FlowCost
from traffic.des import SimConfig, Simulation
from traffic.layout import Layout
from traffic.plans import Goal
from traffic.sipp import ClassGraph


def move_indices(graph: ClassGraph, layout: Layout, start: str, end: str) -> list[int]:
    """The flat indices of every move from `start` to `end` (one per heading at `start`)."""
    u, v = layout.node(start), layout.node(end)
    found = []
    for s, moves in enumerate(graph.moves):
        if graph.node_of[s] == u:
            found += [graph.move_offsets[s] + i for i, m in enumerate(moves) if m[0] == v]
    assert found
    return found


def test_the_cost_counts_the_others_planned_steps_against_and_through() -> None:
    line = Layout.grid({(0, c) for c in range(5)})
    m = manager(line, {"a": "0,0", "b": "0,4"})
    m.plan("a", [Goal("0,2")], 0.0)  # a will drive 0,0 -> 0,1 -> 0,2
    graph = m.graphs[0]
    flow = FlowCost(line, graph, against=10.0, through=1.0)
    a, b = m._vehicles
    cost = flow.costs(m._vehicles, b, 0.0)

    def of(start: str, end: str) -> set[float]:
        return {float(cost[j]) for j in move_indices(graph, line, start, end)}

    assert of("0,3", "0,2") == {1.0}  # into a's route: through only
    assert of("0,2", "0,1") == {11.0}  # head-on against a's step 0,1 -> 0,2, and into 0,1
    assert of("0,1", "0,0") == {10.0}  # against a's first step (a enters 0,0 nowhere)
    assert of("0,0", "0,1") == {1.0}  # along with a: through only
    assert of("0,4", "0,3") == {0.0}  # b's own route (none yet) and nobody else's
    # a's own steps are not counted against a
    assert np.all(flow.costs(m._vehicles, a, 0.0) == 0.0)


def test_own_steps_count_as_if_the_vehicle_were_not_there() -> None:
    grid = Layout.grid(cells(["......", ".@..@.", "......", ".@..@.", "......"]))
    starts = {"a": "0,0", "b": "0,5", "c": "4,0", "d": "4,5", "idle": "2,2"}
    m = manager(grid, starts)
    for name, goal in (("a", "4,3"), ("b", "4,2"), ("c", "0,3"), ("d", "0,2")):
        m.plan(name, [Goal(goal)], 0.0)
    graph = m.graphs[0]
    *planned, idle = m._vehicles
    for own in planned:
        others = [v for v in m._vehicles if v is not own]
        with_own = FlowCost(grid, graph, against=2.0, through=0.5).costs(m._vehicles, own, 0.0)
        # the flow of the others alone, as an idle vehicle (no steps of its own) sees it
        alone = FlowCost(grid, graph, against=2.0, through=0.5).costs(others, idle, 0.0)
        assert len(own.route) > 5
        assert np.allclose(with_own, alone)
        assert alone.sum() > 0


def test_the_counts_are_refreshed_once_per_refresh_interval() -> None:
    line = Layout.grid({(0, c) for c in range(5)})
    m = manager(line, {"a": "0,0", "b": "0,4"})
    graph = m.graphs[0]
    flow = FlowCost(line, graph, against=0.0, through=1.0, refresh=1.0)
    b = m._vehicles[1]
    assert not flow.costs(m._vehicles, b, 0.0).any()
    m.plan("a", [Goal("0,2")], 0.0)
    assert not flow.costs(m._vehicles, b, 0.5).any()  # counted at 0.0: not yet seen
    assert flow.costs(m._vehicles, b, 1.0).sum() > 0


@pytest.mark.parametrize(("cost", "detour"), [(0.5, False), (5.0, True)])
def test_a_search_minimises_arrival_plus_cost(cost: float, detour: bool) -> None:
    ring = Layout.grid({(r, c) for r in range(3) for c in range(3)} - {(1, 1)})
    m = manager(ring, {"a": "0,0"})
    graph = m.graphs[0]
    start, goal = ring.node("0,0"), ring.node("2,2")
    plain = sipp.search(graph, m.table, 0, start, 0, 0.0, sipp.INF, [(goal, 0.0)])
    assert plain is not None
    assert ring.node("0,2") in plain.nodes  # heading east: along the top, one turn (5 s)
    costs = np.zeros(graph.move_offsets[-1])
    costs[move_indices(graph, ring, "0,1", "0,2")] = cost
    path = sipp.search(
        graph, m.table, 0, start, 0, 0.0, sipp.INF, [(goal, 0.0)], move_cost=costs
    )  # fmt: skip
    assert path is not None
    if detour:  # 5 s of cost against 1 s more turning: round by the left, times exact
        assert ring.node("0,2") not in path.nodes
        assert path.arrive[-1] == pytest.approx(plain.arrive[-1] + 1.0)
    else:  # 0.5 s of cost is less than the detour's turn
        assert path == plain


def dense_run(
    congestion: tuple[float, float] | None, **options: object
) -> tuple[object, ListTasks]:
    # (no dead ends: a vehicle idle for good in one, on another's goal, with the other
    # standing at its mouth, is a known gap of stepping aside, docs/TRAFFIC_RESULTS.md)
    grid = Layout.grid(cells(["......", ".@..@.", "......", ".@..@.", "......"]))
    starts = {"a": "0,0", "b": "0,5", "c": "2,0", "d": "2,5", "e": "3,2", "f": "3,5"}
    tasks = {
        "a": [[Goal("2,5")], [Goal("0,0")], [Goal("3,3")], [Goal("0,5")]],
        "b": [[Goal("2,0")], [Goal("0,5")], [Goal("0,2")], [Goal("3,0")]],
        "c": [[Goal("0,5")], [Goal("3,5")], [Goal("2,2")], [Goal("0,1")]],
        "d": [[Goal("0,0")], [Goal("3,0")], [Goal("0,3")], [Goal("2,4")]],
        "e": [[Goal("0,3")], [Goal("2,3")], [Goal("3,2")], [Goal("0,0")]],
        "f": [[Goal("0,2")], [Goal("2,1")], [Goal("3,5")], [Goal("2,3")]],
    }
    m = manager(
        grid, starts, goal_refuge=True, step_aside=True, refuge_penalty=20.0,
        switching=True, congestion=congestion, **options,
    )  # fmt: skip
    source = ListTasks(tasks)
    config = SimConfig(delay_probability=0.0, partial=True, finish_at_goal=True)
    return Simulation(m, source, config).run(600.0), source


@pytest.mark.parametrize("congestion", [None, (1.0, 0.0), (0.0, 0.5), (2.0, 2.0)])
def test_a_dense_lifelong_run_with_costs_finishes_safely(
    congestion: tuple[float, float] | None,
) -> None:
    stats, source = dense_run(congestion)
    assert all(done == 4 for done in source.done.values()), source.done
    assert stats.collisions == 0  # type: ignore[attr-defined]
    assert stats.wait_cycles == 0  # type: ignore[attr-defined]
    assert stats.stalls == 0  # type: ignore[attr-defined]


@settings(
    max_examples=30, deadline=None, suppress_health_check=[HealthCheck.too_slow], derandomize=True
)
@given(
    scenarios(),
    st.integers(0, 10_000),
    st.sampled_from([0.0, 0.3]),
    st.sampled_from([(1.0, 0.0), (0.0, 1.0), (3.0, 3.0)]),
)
def test_random_tasks_and_delays_with_costs_never_deadlock(  # type: ignore[no-untyped-def]
    scenario, seed, delay_probability, congestion
):
    layout, starts, tasks = scenario
    source = ListTasks(tasks)
    m = manager(layout, starts, congestion=congestion)
    stats = CheckedSimulation(m, source, delayed(seed, delay_probability)).run(3000.0)
    assert_all_done_safely(stats, source, tasks)
