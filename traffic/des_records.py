"""What a discrete-event run (`traffic.des`) is given and what it measures.

`Tasks` is where vehicles go next, `SimConfig` the disturbances, fallbacks and safety-net
thresholds of a run; `TaskRecord` and `SimStats` are its results, which the benchmark turns into
figures (`bench.traffic`).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Protocol

from traffic.plans import Goal


class Tasks(Protocol):
    """Where vehicles go next."""

    def next_goals(self, vehicle_id: str, node: str, now: float) -> list[Goal] | None:
        """The next task's goals for a vehicle standing at `node`, or None for no task."""

    def finished(self, vehicle_id: str, goals: Sequence[Goal], now: float) -> None:
        """The vehicle completed the task with `goals`."""


class ReassigningTasks(Tasks, Protocol):
    """A task source that can give a task whose plan keeps failing other goals (as a WMS would
    give an order another workstation)."""

    def reassign(
        self, vehicle_id: str, goals: Sequence[Goal], node: str, now: float
    ) -> list[Goal] | None:
        """Other goals for the task with `goals` (not yet started), or None to keep them."""


@dataclass
class SimConfig:
    """Disturbances, fallbacks and safety-net thresholds of a run."""

    delay_probability: float = 0.05
    delay_range: tuple[float, float] = (5.0, 30.0)
    seed: int = 0
    retry_after: float = 1.0  # s until a vehicle without a plan tries again
    retry_backoff: float = 1.0  # the wait grows by this factor per failed plan in a row
    retry_max: float = 30.0  # s: the longest wait between two tries
    # after this many failed plans in a row for a task not yet started, ask the task source
    # for other goals (`ReassigningTasks.reassign`); 0: never
    reassign_after: int = 0
    partial: bool = False  # on failure, drive towards the goal as far as possible
    stall_after: float = 300.0  # s without progress while work is left
    check_every: float = 10.0  # s between wait-for-cycle checks
    tick_every: float = 1.0  # s between manager ticks (re-timing, re-planning waiting vehicles)
    replan_budget: int = 2  # re-plans per tick
    # a task is done when the vehicle passes its last goal, and the next one is planned from
    # there (for a manager with goal_refuge: its plans go on from the goal to a refuge)
    finish_at_goal: bool = False
    # a vehicle with a task but driving another route (on to its refuge after a failed plan,
    # or sent aside) tries its task's plan again whenever it stands at a node on the way (its
    # decision point, waiting for its base), at most once per `retry_after` s, instead of
    # only at the end of that route
    retry_on_the_way: bool = False


@dataclass
class TaskRecord:
    """One completed task."""

    vehicle_id: str
    goals: tuple[Goal, ...]
    assigned: float
    done: float
    start: int  # node index where it was assigned
    heading: int
    delay: float  # injected delay while executing it


@dataclass
class SimStats:
    """What a run measured."""

    tasks: list[TaskRecord] = field(default_factory=list)
    collisions: int = 0
    wait_cycles: int = 0
    stalls: int = 0  # no progress for stall_after s, and neither the vehicle it waits for
    long_waits: int = 0  # no progress for stall_after s behind a vehicle that is driving
    stall_chains: list[str] = field(default_factory=list)  # per stall: its wait-for chain
    plan_failures: int = 0
    reassigned: int = 0  # tasks given other goals after failed plans (SimConfig.reassign_after)
    moves: int = 0
    delays: int = 0
    waits: list[float] = field(default_factory=list)  # seconds stopped at decision points
    plan_seconds: list[float] = field(default_factory=list)  # wall time per successful plan call
    release_seconds: list[float] = field(default_factory=list)  # wall time per progress event
    # the same in process CPU time: on a shared, loaded machine wall time also counts waiting
    # for a core, which says more about the neighbours than about the algorithm
    plan_cpu_seconds: list[float] = field(default_factory=list)
    release_cpu_seconds: list[float] = field(default_factory=list)
    replan_cpu_seconds: list[float] = field(default_factory=list)  # per tick() call
