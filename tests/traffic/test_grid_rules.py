"""Grid rules (LoRR, S2): cells instead of footprints, and a vehicle may follow one cell behind.

Under grid rules a node is held until `GRID_LEAVE` s after its vehicle leaves it (`on_leave`),
not until the vehicle reaches the next node. These tests check the planned times (following
one cell behind, never two vehicles leaving each other's cells at once), the clearing on
leaving, the re-timing, both search loops, and that random runs with delays (stays before a
move), with and without switching, still never collide or deadlock.
"""

from types import SimpleNamespace
from typing import Any

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from tests.traffic.helpers import AMR, ListTasks, cells, manager
from tests.traffic.test_congestion import dense_run
from tests.traffic.test_deadlock_property import (
    CheckedSimulation,
    assert_all_done_safely,
    delayed,
    scenarios,
)
from tests.traffic.test_retiming import retimed_run
from tests.traffic.test_speedups import BothLoops, needs_native
from traffic import sipp, timing
from traffic.des import SimConfig, Simulation
from traffic.footprint import ConflictSets
from traffic.layout import Layout
from traffic.plans import GRID_LEAVE, Goal

CORRIDOR = Layout.grid(cells(["........"]))


def convoy(grid_rules: bool) -> Any:
    """B stands right behind A in a corridor, both heading east to its far end."""
    m = manager(CORRIDOR, {"A": "0,1", "B": "0,0"}, grid_rules=grid_rules)
    m.plan("A", [Goal("0,7")], 0.0)
    m.plan("B", [Goal("0,6")], 0.0)
    return m


def test_under_grid_rules_every_resource_conflicts_only_with_itself() -> None:
    grid = ConflictSets.cells(CORRIDOR, [AMR])
    footprints = ConflictSets(CORRIDOR, [AMR])
    for r in range(CORRIDOR.resource_count):
        assert grid.of(0, r) == (r,)
    node, segment = CORRIDOR.node("0,1"), CORRIDOR.segment_resource(0)
    assert footprints.conflict(0, segment, node) or footprints.conflict(0, node, segment)


def test_a_follower_drives_one_cell_behind_under_grid_rules() -> None:
    for grid_rules, behind in ((False, 2.0), (True, 1.0)):
        m = convoy(grid_rules)
        a, b = m.vehicle("A"), m.vehicle("B")
        assert a.arrive[-1] == pytest.approx(6.0)  # alone ahead: 6 cells at 1 m/s
        # B reaches each cell `behind` s after A did (A reached node k + 1 at k s)
        for k in range(1, len(b.route)):
            assert b.arrive[k] == pytest.approx(a.arrive[k - 1] + behind, abs=0.05)
        if grid_rules:  # ... and leaves each cell strictly after A left the next one (two
            # vehicles setting off at once into each other's cells could form a ring, where
            # each waits for the next to leave first)
            for k in range(len(b.route) - 1):
                assert b.depart[k] > a.depart[k]
                assert b.depart[k] >= a.depart[k] + GRID_LEAVE - 1e-9


@pytest.mark.parametrize("grid_rules", [False, True])
def test_the_convoy_drives_without_collision_and_faster_under_grid_rules(
    grid_rules: bool,
) -> None:
    m = manager(CORRIDOR, {"A": "0,1", "B": "0,0"}, grid_rules=grid_rules)
    source = ListTasks({"A": [[Goal("0,7")]], "B": [[Goal("0,6")]]})
    stats = Simulation(m, source, SimConfig(delay_probability=0.0)).run(60.0)
    assert source.done == {"A": 1, "B": 1}
    assert stats.collisions == 0
    finished = max(t.done for t in stats.tasks)
    assert finished == pytest.approx(6.0 if grid_rules else 7.0, abs=0.05)


def test_leaving_a_node_clears_its_hold_and_lets_the_follower_go() -> None:
    m = manager(CORRIDOR, {"A": "0,1", "B": "0,0"}, grid_rules=True)
    m.plan("A", [Goal("0,7")], 0.0)
    b_plan = m.plan("B", [Goal("0,6")], 0.0)
    a, b = m.vehicle("A"), m.vehicle("B")
    assert a.base > 0
    assert b.base == 0  # B waits for A's cell
    assert b_plan.base_end == 0
    held = a.node_holds[0]
    releases = m.on_leave("A", 0.0)
    assert held not in m.table.blocked[held.resource]
    assert [r.vehicle_id for r in releases] == ["B"]
    assert b.base > 0
    assert m.on_leave("A", 0.0) == []  # left once
    m.on_progress("A", 1, 1.0)  # the cleared hold is not cleared again
    assert a.passed == 1


def test_without_grid_rules_leaving_clears_nothing() -> None:
    m = convoy(False)
    a = m.vehicle("A")
    assert m.on_leave("A", 0.0) == []
    assert a.node_holds[0] in m.table.blocked[a.node_holds[0].resource]


def test_re_timing_under_grid_rules_ends_a_node_hold_just_after_the_departure() -> None:
    m = convoy(True)
    a = m.vehicle("A")
    timing.propagate(m._vehicles, m.table, m.graphs, [(3.0, a.idx, 2)], m.leave)
    assert a.depart[2] == pytest.approx(3.0)
    assert a.node_holds[2].end == pytest.approx(3.0 + GRID_LEAVE)
    assert a.edge_holds[3] is not None
    assert a.edge_holds[3].end == pytest.approx(4.0)
    b = m.vehicle("B")
    # B (one cell behind: its index k + 1 is A's k) was pushed to enter A's cell after it
    assert b.node_holds[3].start == pytest.approx(a.node_holds[2].end)
    assert b.depart[2] == pytest.approx(3.0 + GRID_LEAVE)


@needs_native
def test_both_re_timings_agree_under_grid_rules(monkeypatch: pytest.MonkeyPatch) -> None:
    plain, _ = retimed_run(monkeypatch, timing.propagate_plain, grid_rules=True)
    compiled, moved = retimed_run(monkeypatch, timing.propagate, grid_rules=True)
    assert compiled == plain
    (_, collisions, _, delays, _, wait_cycles, stalls), done = plain[0], plain[1]
    assert sum(done.values()) == 15
    assert (collisions, wait_cycles, stalls) == (0, 0, 0)
    assert delays > 0
    assert moved > 0


# (with costs 0.5, 0.5 or 1, 0 this map meets the known gap of idle vehicles for good: the
# last vehicle's goal is reachable only through cells where finished vehicles stay, and
# stepping aside finds no refuge off its route for them; docs/TRAFFIC_RESULTS.md)
@pytest.mark.parametrize("congestion", [None, (0.0, 0.5), (2.0, 2.0)])
def test_a_dense_lifelong_run_under_grid_rules_finishes_safely(
    congestion: tuple[float, float] | None,
) -> None:
    stats, source = dense_run(congestion, grid_rules=True)
    assert all(done == 4 for done in source.done.values()), source.done
    assert stats.collisions == 0  # type: ignore[attr-defined]
    assert stats.wait_cycles == 0  # type: ignore[attr-defined]
    assert stats.stalls == 0  # type: ignore[attr-defined]


@needs_native
def test_searches_under_grid_rules_search_the_same(monkeypatch: pytest.MonkeyPatch) -> None:
    loops = BothLoops()
    monkeypatch.setattr(sipp, "LOOP", SimpleNamespace(run=loops.run))
    _, source = dense_run((2.0, 2.0), grid_rules=True)
    assert sum(source.done.values()) == 24
    assert loops.found > 30


@settings(
    max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow], derandomize=True
)
@given(scenarios(), st.integers(0, 10_000), st.sampled_from([0.0, 0.3]), st.booleans())
def test_random_tasks_and_delays_under_grid_rules_never_deadlock(  # type: ignore[no-untyped-def]
    scenario, seed, delay_probability, switching
):
    layout, starts, tasks = scenario
    source = ListTasks(tasks)
    m = manager(layout, starts, grid_rules=True, switching=switching)
    stats = CheckedSimulation(m, source, delayed(seed, delay_probability)).run(3000.0)
    assert_all_done_safely(stats, source, tasks)
