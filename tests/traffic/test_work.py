"""Work done (`rho_work`): finished tasks plus the covered share of the tasks still open, in the
traffic run (`bench.traffic.fleet.run`) and in the ghost run alike."""

import pytest

from bench.traffic.fleet import ghost, run
from tests.traffic.helpers import ListTasks, cells, manager
from traffic.des import SimConfig, Simulation
from traffic.layout import Layout
from traffic.plans import Goal

LANE = Layout.grid(cells(["..........."]))  # 0,0 .. 0,10: ten 1 m moves east


def test_a_task_cut_halfway_counts_half() -> None:
    m = manager(LANE, {"a": "0,0"})
    config = SimConfig(delay_probability=0.0)
    result = run(m, ListTasks({"a": [[Goal("0,10")]]}), 5.0, config)
    assert result.stats.tasks == []  # not finished at 5 s
    assert result.work == pytest.approx(0.5)  # 5 of its 10 free-flow seconds covered


def test_finished_tasks_count_whole_and_the_next_one_in_part() -> None:
    m = manager(LANE, {"a": "0,0"})
    config = SimConfig(delay_probability=0.0)
    # 10 s east, then back west (2 s to turn round, 10 s to drive): at 16 s 6 of those
    # 12 s are covered
    tasks = ListTasks({"a": [[Goal("0,10")], [Goal("0,0")]]})
    result = run(m, tasks, 16.0, config)
    assert len(result.stats.tasks) == 1
    assert result.work == pytest.approx(1.5)


def test_open_tasks_are_the_ones_not_finished() -> None:
    m = manager(LANE, {"a": "0,0", "b": "0,10"})
    tasks = ListTasks({"a": [[Goal("0,4")]], "b": [[Goal("0,6")]]})
    sim = Simulation(m, tasks, SimConfig(delay_probability=0.0))
    sim.run(1.0)
    assert {name for name, *_ in sim.open_tasks()} == {"a", "b"}
    sim.run(30.0)
    assert sim.open_tasks() == []


def test_the_ghost_counts_the_open_task_by_its_elapsed_share() -> None:
    m = manager(LANE, {"a": "0,0"})
    config = SimConfig(delay_probability=0.0)
    finished, work = ghost(m, [("0,0", 0.0)], _Repeat("0,10", "0,0"), 15.0, config)
    # east in 10 s, then west: 2 s to turn round and 10 s to drive, 5 of 12 s done at 15 s
    assert finished == 1
    assert work == pytest.approx(1 + 5 / 12)


class _Repeat:
    """Goals alternating between two nodes, for ever."""

    def __init__(self, *nodes: str) -> None:
        self.nodes, self.k = nodes, 0

    def next_goals(self, vehicle_id: str, node: str, now: float) -> list[Goal]:
        goal = self.nodes[self.k % len(self.nodes)]
        self.k += 1
        return [Goal(goal)]

    def finished(self, vehicle_id: str, goals: object, now: float) -> None:
        pass
