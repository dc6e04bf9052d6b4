"""The compiled planner parts (`traffic._speedups`) give exactly what their plain twins give."""

import json
import os
import subprocess
import sys
from types import SimpleNamespace
from typing import Any

import pytest

from tests.traffic.helpers import ListTasks, cells, manager
from tests.traffic.test_congestion import dense_run
from tests.traffic.test_planning_speed import busy_grid
from traffic import reservations, sipp, sipp_loop, speedups
from traffic.des import SimConfig, Simulation
from traffic.layout import Layout
from traffic.plans import Goal

native = speedups.COMPILED  # None when not built (`make venv` builds it) or FLEET_TRAFFIC_PURE
needs_native = pytest.mark.skipif(native is None, reason="compiled planner parts not loaded")


class BothLoops:
    """Runs every search through both loops and insists on the same answer."""

    def __init__(self) -> None:
        self.found = self.failed = 0

    def run(self, problem: Any) -> Any:
        plain = sipp_loop.run(problem)
        compiled = native.run(problem)  # type: ignore[union-attr]
        assert compiled == plain, (problem.start, problem.goals, problem.partial, problem.refuge)
        if plain is None:
            self.failed += 1
        else:
            self.found += 1
        return compiled


@pytest.fixture
def both(monkeypatch: pytest.MonkeyPatch) -> BothLoops:
    loops = BothLoops()
    monkeypatch.setattr(sipp, "LOOP", SimpleNamespace(run=loops.run))
    return loops


@needs_native
def test_a_delayed_run_with_partial_plans_searches_the_same(both: BothLoops) -> None:
    _, sim, tasks = busy_grid()
    stats = sim.run(400.0)
    assert sum(tasks.done.values()) == 15
    assert stats.collisions == 0
    assert both.found > 20  # plans, re-plans and partial plans compared


@needs_native
def test_bounded_searches_that_give_up_search_the_same(both: BothLoops) -> None:
    _, sim, _ = busy_grid(quick_search=(3, 2.0))
    sim.run(300.0)
    assert both.found > 10


@needs_native
def test_refuge_searches_with_avoided_nodes_and_costs_search_the_same(both: BothLoops) -> None:
    grid = Layout.grid(cells(["......", ".@..@.", "......", ".@..@."]))
    starts = {"a": "0,0", "b": "0,5", "c": "2,0", "d": "2,5", "e": "3,2"}
    tasks = {
        "a": [[Goal("2,5")], [Goal("0,0")], [Goal("3,3")]],
        "b": [[Goal("2,0")], [Goal("0,5")], [Goal("0,2")]],
        "c": [[Goal("0,5")], [Goal("3,5")], [Goal("2,2")]],
        "d": [[Goal("0,0")], [Goal("3,0")], [Goal("0,3")]],
        "e": [[Goal("0,3")], [Goal("2,3")], [Goal("3,2")]],
    }
    m = manager(grid, starts, goal_refuge=True, step_aside=True, refuge_penalty=20.0)
    config = SimConfig(delay_probability=0.0, partial=True, finish_at_goal=True)
    Simulation(m, ListTasks(tasks), config).run(400.0)
    assert both.found > 15


@needs_native
@pytest.mark.parametrize("congestion", [(1.0, 0.0), (0.0, 0.5), (2.0, 2.0)])
def test_searches_with_a_congestion_cost_search_the_same(
    both: BothLoops, congestion: tuple[float, float]
) -> None:
    _, source = dense_run(congestion)
    assert sum(source.done.values()) == 24
    assert both.found > 30


@needs_native
def test_a_start_with_an_unknown_heading_and_a_blocked_goal_search_the_same(
    both: BothLoops,
) -> None:
    layout = Layout.grid({(r, c) for r in range(3) for c in range(4)})
    m = manager(layout, {"a": "0,0"})
    m.add_vehicle("b", "2,3", 0.0)  # no heading: the start is no graph state
    m.plan("b", [Goal("0,3", 1.0), Goal("1,1", 1.0)], 0.0)
    graph, table = m.graphs[0], m.table
    paths = {
        (goal, partial): sipp.search(
            graph,
            table,
            1,
            layout.node("2,3"),
            sipp.ANY_HEADING,
            0.0,
            sipp.INF,
            [(layout.node(goal), 0.0)],
            partial=partial,
        )  # fmt: skip
        for goal in ("0,0", "2,0")  # a stands on 0,0 for good: a partial path or nothing
        for partial in (False, True)
    }
    assert paths[("0,0", False)] is None
    partial_path = paths[("0,0", True)]
    assert partial_path is not None
    assert not partial_path.complete
    whole_path = paths[("2,0", False)]
    assert whole_path is not None
    assert whole_path.complete
    assert both.found == 4  # b's plan, the partial path and both paths to 2,0


@pytest.mark.skipif(os.environ.get("CI") != "true", reason="CI builds the compiled loop")
def test_ci_searches_with_the_compiled_loop() -> None:
    assert native is not None, "build_native.py did not build traffic._speedups"
    assert sipp.LOOP is native
    assert reservations.Hold is native.Hold


RUN = """
import json
from tests.traffic.test_planning_speed import busy_grid
from traffic import speedups
m, sim, tasks = busy_grid()
stats = sim.run(400.0)
done = tasks.done
{report}
"""

# switching on (`traffic.switching`): the switches push late vehicles through `propagate`
RUN_SWITCHING = """
import json
from tests.traffic.test_switching import small_warehouse
from traffic import speedups
from traffic.des import SimConfig, Simulation
m, tasks = small_warehouse(seed=1)
stats = Simulation(m, tasks, SimConfig(seed=1, retry_backoff=2.0, reassign_after=3)).run(600.0)
done = [m.switches, m.switch_pushes, m.switches_dropped]
{report}
"""

REPORT = """
plans = {v.name: (v.route, v.arrive, v.depart) for v in m._vehicles}
holds = sorted(repr(h) for queue in m.table.blocked for h in queue)
outcome = [repr(stats.tasks), stats.collisions, stats.wait_cycles, stats.stalls, stats.moves,
           stats.delays, stats.waits]
print(json.dumps([speedups.COMPILED is not None, outcome, done, plans, holds]))
"""


@needs_native
@pytest.mark.parametrize("script", [RUN, RUN_SWITCHING], ids=["busy-grid", "switching"])
def test_a_delayed_run_retimes_and_holds_the_same_compiled_and_plain(script: str) -> None:
    def run(pure: str) -> list[Any]:
        env = os.environ | {"FLEET_TRAFFIC_PURE": pure}
        code = script.format(report=REPORT)
        out = subprocess.run(
            [sys.executable, "-c", code], env=env, capture_output=True, text=True, check=True
        )
        result: list[Any] = json.loads(out.stdout)
        return result

    compiled, plain = run("0"), run("1")
    assert (compiled[0], plain[0]) == (True, False)
    assert compiled[1:] == plain[1:]
