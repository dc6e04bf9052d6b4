"""What a discrete-event run (`traffic.des`) is given and what it measures.

`Tasks` is where vehicles go next, `SimConfig` the disturbances, fallbacks and safety-net
thresholds of a run; `TaskRecord` and `SimStats` are its results, which the benchmark turns into
figures (`bench.traffic`).
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Sequence
from dataclasses import dataclass, field
from typing import Any, Protocol

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


class Timings:
    """Durations kept as a histogram of 1 %-wide buckets on a log scale, with the exact count,
    sum and maximum: percentiles within 1 % in constant memory however many samples come (an
    8 h S3 run times about 10 million state messages, which as a list of floats made most of
    a saved run, `bench.traffic --state`)."""

    GROWTH = 1.01  # bucket k holds (GROWTH**(k-1), GROWTH**k]
    _LOG = math.log(GROWTH)

    def __init__(self, samples: Iterable[float] = ()) -> None:
        self.buckets: dict[int, int] = {}
        self.zeros = 0  # samples of 0 s or less (a clock that did not tick)
        self.count = 0
        self.total = 0.0
        self.max = 0.0
        for seconds in samples:
            self.append(seconds)

    def append(self, seconds: float) -> None:
        """Count one duration."""
        self.count += 1
        self.total += seconds
        if seconds <= 0.0:
            self.zeros += 1
            return
        self.max = max(self.max, seconds)
        bucket = math.ceil(math.log(seconds) / self._LOG)
        self.buckets[bucket] = self.buckets.get(bucket, 0) + 1

    def __len__(self) -> int:
        return self.count

    def percentile(self, q: float) -> float:
        """The sample of rank ⌊count·q/100⌋ in ascending order (as sorting a list would give),
        as its bucket's upper edge, never above the maximum: at most 1 % high."""
        if not self.count:
            return 0.0
        rank = min(self.count - 1, int(self.count * q / 100))
        seen = self.zeros
        if rank < seen:
            return 0.0
        for bucket in sorted(self.buckets):
            seen += self.buckets[bucket]
            if rank < seen:
                return min(self.max, self.GROWTH**bucket)
        return self.max

    def count_over(self, seconds: float) -> int:
        """How many samples exceeded `seconds`, to the bucket: those in the bucket holding
        `seconds` (at most 1 % above it) are not counted."""
        if seconds <= 0.0:
            return self.count - self.zeros
        edge = math.ceil(math.log(seconds) / self._LOG)
        return sum(n for bucket, n in self.buckets.items() if bucket > edge)

    def __eq__(self, other: object) -> bool:
        if not isinstance(other, Timings):
            return NotImplemented
        return (self.buckets, self.zeros, self.count, self.max) == (
            other.buckets,
            other.zeros,
            other.count,
            other.max,
        )


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
    release_seconds: Timings = field(default_factory=Timings)  # wall time per progress event
    # the same in process CPU time: on a shared, loaded machine wall time also counts waiting
    # for a core, which says more about the neighbours than about the algorithm
    plan_cpu_seconds: list[float] = field(default_factory=list)
    release_cpu_seconds: Timings = field(default_factory=Timings)
    replan_cpu_seconds: list[float] = field(default_factory=list)  # per tick() call

    def __setstate__(self, state: dict[str, Any]) -> None:
        """A run saved before the release timings were histograms kept them as lists."""
        for name in ("release_seconds", "release_cpu_seconds"):
            if isinstance(state.get(name), list):
                state[name] = Timings(state[name])
        self.__dict__.update(state)
