"""A vehicle whose plan keeps failing tries again after growing waits (SimConfig.retry_backoff),
so a goal that stays taken does not cost a full search every second."""

from collections.abc import Sequence

from bench.traffic.fleet import WarehouseTasks
from bench.traffic.maps import warehouse
from tests.traffic.helpers import cells, manager, simulate
from traffic.des import SimConfig, SimStats, Simulation
from traffic.layout import Layout
from traffic.plans import Goal

CORRIDOR = Layout.grid(cells(["......"]))


def _failures(config: SimConfig) -> int:
    # A stands on B's goal for good (it has nothing to do), so B can never plan.
    stats, _ = simulate(
        CORRIDOR,
        {"A": "0,5", "B": "0,0"},
        {"B": [[Goal("0,5", 1.0)]]},
        until=100.0,
        config=config,
    )
    assert stats.tasks == []
    return stats.plan_failures


def test_constant_retries_by_default() -> None:
    assert _failures(SimConfig(delay_probability=0.0)) == 101  # at 0, 1, ..., 100 s


def test_retries_back_off_to_the_longest_wait() -> None:
    config = SimConfig(delay_probability=0.0, retry_backoff=2.0, retry_max=30.0)
    # tries at 0, 1, 3, 7, 15, 31, then every 30 s: 61, 91
    assert _failures(config) == 8


class _OtherDrop:
    """Tasks whose goal can be swapped for another one (ReassigningTasks)."""

    def __init__(self) -> None:
        self.todo = [[Goal("0,5", 1.0)]]
        self.asked: list[tuple[str, str, float]] = []
        self.finished_goals: list[str] = []

    def next_goals(self, vehicle_id: str, node: str, now: float) -> list[Goal] | None:
        return self.todo.pop(0) if vehicle_id == "B" and self.todo else None

    def finished(self, vehicle_id: str, goals: Sequence[Goal], now: float) -> None:
        self.finished_goals.append(goals[-1].node)

    def reassign(
        self, vehicle_id: str, goals: Sequence[Goal], node: str, now: float
    ) -> list[Goal] | None:
        self.asked.append((vehicle_id, node, now))
        return [Goal("0,2", goals[-1].dwell)]


def _reassigned(after: int) -> tuple[SimStats, _OtherDrop]:
    tasks = _OtherDrop()
    config = SimConfig(delay_probability=0.0, retry_backoff=2.0, reassign_after=after)
    sim = Simulation(manager(CORRIDOR, {"A": "0,5", "B": "0,0"}), tasks, config)
    return sim.run(100.0), tasks


def test_an_order_that_keeps_failing_gets_other_goals() -> None:
    stats, tasks = _reassigned(3)
    # failures at 0, 1, 3 s; the third asks for other goals, which plan at the next try (4 s)
    assert stats.plan_failures == 3
    assert tasks.asked == [("B", "0,0", 3.0)]
    assert stats.reassigned == 1
    assert tasks.finished_goals == ["0,2"]
    assert [t.goals[-1].node for t in stats.tasks] == ["0,2"]
    assert stats.collisions == 0


def test_no_reassignment_unless_configured() -> None:
    stats, tasks = _reassigned(0)
    assert tasks.asked == []
    assert stats.tasks == []
    assert stats.reassigned == 0


def test_warehouse_orders_move_to_another_free_workstation() -> None:
    grid = warehouse()
    tasks = WarehouseTasks(grid, 1, ["v0", "v1"])
    first = tasks.next_goals("v0", "x", 0.0)
    other = tasks.next_goals("v1", "x", 0.0)
    assert first is not None
    assert other is not None
    moved = tasks.reassign("v0", first, "x", 5.0)
    assert moved is not None
    assert moved[0] == first[0]  # the same pick
    assert moved[1].node not in (first[1].node, other[1].node)
    assert moved[1].node in tasks.stations
    assert moved[1].dwell == first[1].dwell
    # the old workstation is free for other orders, the new one is taken
    assert first[1].node not in tasks._targeted
    assert moved[1].node in tasks._targeted
