"""A discrete-event execution of traffic plans, faster than real time (tests and benchmarks).

Vehicles drive only what the manager released: one step at a time (turn on the spot, drive the
edge), optionally delayed at random, and report each node reached with `on_progress`. When a
vehicle ends its route it gets its next task from a `Tasks` source. Independently of the
manager's bookkeeping the executor tracks what each vehicle physically occupies (its node, and
while moving the segment and the next node) and counts a collision whenever a vehicle starts a
move into resources that conflict with another vehicle's. It also counts wait-for cycles and
stalls (a vehicle with work left that has not moved for `stall_after` seconds).
"""

from __future__ import annotations

import heapq
import random
import time
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Protocol

from traffic.manager import NoPlanError, TrafficManager
from traffic.plans import Goal, Plan, Release
from traffic.reservations import INF, ReservationTable
from traffic.sipp import ClassGraph, search

MOVE, RETRY, CHECK = 0, 1, 2


class Tasks(Protocol):
    """Where vehicles go next."""

    def next_goals(self, vehicle_id: str, node: str, now: float) -> list[Goal] | None:
        """The next task's goals for a vehicle standing at `node`, or None for no task."""

    def finished(self, vehicle_id: str, goals: Sequence[Goal], now: float) -> None:
        """The vehicle completed the task with `goals`."""


@dataclass
class SimConfig:
    """Disturbances, fallbacks and safety-net thresholds of a run."""

    delay_probability: float = 0.05
    delay_range: tuple[float, float] = (5.0, 30.0)
    seed: int = 0
    retry_after: float = 1.0  # s until a vehicle without a plan tries again
    partial: bool = False  # on failure, drive towards the goal as far as possible
    stall_after: float = 300.0  # s without progress while work is left
    check_every: float = 10.0  # s between wait-for-cycle checks
    tick_every: float = 1.0  # s between manager ticks (re-timing, re-planning waiting vehicles)
    replan_budget: int = 2  # re-plans per tick
    # a task is done when the vehicle passes its last goal, and the next one is planned from
    # there (for a manager with goal_refuge: its plans go on from the goal to a refuge)
    finish_at_goal: bool = False


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


class _Car:
    __slots__ = (
        "name",
        "idx",
        "moving",
        "goals",
        "assigned",
        "start",
        "heading",
        "delay",
        "occupied",
        "waiting_since",
        "last_move",
        "rng",
        "task_plan",
        "stalled",
    )

    def __init__(self, name: str, idx: int, rng: random.Random) -> None:
        self.name, self.idx, self.rng = name, idx, rng
        self.moving = False
        self.goals: list[Goal] | None = None
        self.assigned = self.delay = 0.0
        self.start = self.heading = 0
        self.occupied: tuple[int, ...] = ()
        self.waiting_since = -1.0
        self.last_move = 0.0
        self.task_plan = False  # the current route serves the task (not a detour or parking)
        self.stalled = False


class Simulation:
    """Runs a manager's vehicles through their tasks in simulated time."""

    def __init__(self, manager: TrafficManager, tasks: Tasks, config: SimConfig) -> None:
        self.manager, self.tasks, self.config = manager, tasks, config
        self.stats = SimStats()
        self.now = 0.0
        self._events: list[tuple[float, int, int, int]] = []
        self._seq = 0
        self._cars = [
            _Car(name, i, random.Random(config.seed * 100_003 + i))  # noqa: S311 (simulation)
            for i, name in enumerate(manager.vehicle_ids)
        ]
        self._by_name = {c.name: c for c in self._cars}
        self._occupant: dict[int, set[int]] = {}
        for car in self._cars:
            node = manager.vehicle(car.name).route[-1]
            self._occupy(car, (node,))

    def run(self, until: float) -> SimStats:
        """Simulate until `until` seconds of plan time."""
        if self.now == 0.0:
            for car in self._cars:
                self._next_task(car)
            self._push(self.config.check_every, CHECK, -1)
            self._push(self.config.tick_every, CHECK, -2)
        while self._events and self._events[0][0] <= until:
            self.now, _, kind, idx = heapq.heappop(self._events)
            if kind == MOVE:
                self._arrive(self._cars[idx])
            elif kind == RETRY:
                self._try_plan(self._cars[idx])
            elif idx == -1:
                self._check()
                self._push(self.now + self.config.check_every, CHECK, -1)
            else:
                cpu = time.process_time()
                releases = self.manager.tick(self.now, budget=self.config.replan_budget)
                self.stats.replan_cpu_seconds.append(time.process_time() - cpu)
                self._apply(releases)
                self._push(self.now + self.config.tick_every, CHECK, -2)
        self.now = until
        return self.stats

    def _push(self, at: float, kind: int, idx: int) -> None:
        self._seq += 1
        heapq.heappush(self._events, (at, self._seq, kind, idx))

    # -- tasks and planning -------------------------------------------------------------------

    def _next_task(self, car: _Car) -> None:
        v = self.manager.vehicle(car.name)
        node = v.route[v.passed]
        car.goals = self.tasks.next_goals(car.name, self.manager.layout.node_ids[node], self.now)
        car.assigned, car.delay = self.now, 0.0
        car.start, car.heading = node, v.headings[v.passed]
        car.last_move = self.now
        if car.goals is None:
            if self.manager.layout.parking and node not in self.manager.layout.parking:
                self._park(car)
            return
        self._try_plan(car)

    def _try_plan(self, car: _Car) -> None:
        if car.goals is None or car.moving:
            return
        began, cpu = time.perf_counter(), time.process_time()
        try:
            plan = self.manager.plan(car.name, car.goals, self.now)
        except NoPlanError as failed:
            self.stats.plan_failures += 1
            self._apply(failed.releases)  # vehicles sent aside on the way
            self._fallback(car)
            return
        self.stats.plan_seconds.append(time.perf_counter() - began)
        self.stats.plan_cpu_seconds.append(time.process_time() - cpu)
        car.task_plan = True
        self._started(car, plan)

    def _fallback(self, car: _Car) -> None:
        layout, v = self.manager.layout, self.manager.vehicle(car.name)
        if self.config.finish_at_goal and v.passed < len(v.route) - 1:
            # the route goes on (to the refuge): drive it, plan again at its end
            self._apply(self.manager.proceed(car.name, self.now))
            return
        if layout.parking and v.route[-1] not in layout.parking:
            if self._park(car):
                return
        elif self.config.partial and car.goals is not None and len(car.goals) == 1:
            try:
                plan = self.manager.plan(car.name, car.goals, self.now, partial=True)
            except NoPlanError:
                pass
            else:
                car.task_plan = False
                self._started(car, plan)
                return
        self._push(self.now + self.config.retry_after, RETRY, car.idx)

    def _park(self, car: _Car) -> bool:
        try:
            plan = self.manager.park(car.name, self.now)
        except NoPlanError:
            return False
        car.task_plan = False
        self._started(car, plan)
        return True

    def _started(self, car: _Car, plan: Plan) -> None:
        self._apply(plan.releases)
        if self.config.finish_at_goal:
            if self._at_goal(car):  # it stands on its goal already
                self._goal_done(car)
        elif len(plan.nodes) == 1:  # already there
            self._route_done(car)

    # -- execution ------------------------------------------------------------------------------

    def _apply(self, releases: Sequence[Release]) -> None:
        for release in releases:
            car = self._by_name[release.vehicle_id]
            if not car.moving:
                self._depart(car)

    def _depart(self, car: _Car) -> None:
        manager = self.manager
        v = manager.vehicle(car.name)
        p = v.passed
        if p >= v.base:
            if p < len(v.route) - 1 and car.waiting_since < 0:
                car.waiting_since = self.now
            return
        if car.waiting_since >= 0:
            self.stats.waits.append(self.now - car.waiting_since)
            car.waiting_since = -1.0
        graph = manager.graphs[v.cls]
        u, n = v.route[p], v.route[p + 1]
        duration = max(0.0, v.ready_at - self.now) + graph.turn(v.headings[p], v.headings[p + 1])
        duration += graph.travel[(u, n)]
        config = self.config
        if car.rng.random() < config.delay_probability:
            extra = car.rng.uniform(*config.delay_range)
            duration += extra
            car.delay += extra
            self.stats.delays += 1
        edge = v.edge_holds[p + 1]
        assert edge is not None  # every step after the first has its segment hold
        self._occupy(car, (u, edge.resource, n))
        car.moving = True
        self.stats.moves += 1
        self._push(self.now + duration, MOVE, car.idx)

    def _arrive(self, car: _Car) -> None:
        manager = self.manager
        v = manager.vehicle(car.name)
        car.moving = False
        car.last_move = self.now
        car.stalled = False
        passed = v.passed + 1
        self._occupy(car, (v.route[passed],))
        began, cpu = time.perf_counter(), time.process_time()
        releases = manager.on_progress(car.name, passed, self.now)
        self.stats.release_seconds.append(time.perf_counter() - began)
        self.stats.release_cpu_seconds.append(time.process_time() - cpu)
        self._apply(releases)
        if self.config.finish_at_goal and self._at_goal(car):
            self._goal_done(car)
            v = manager.vehicle(car.name)
            if not car.moving and v.passed < len(v.route) - 1:
                self._depart(car)
            return
        if passed == len(v.route) - 1:
            self._route_done(car)
        elif not car.moving:
            self._depart(car)

    def _at_goal(self, car: _Car) -> bool:
        """Whether the vehicle has passed the last goal of its task on a plan for that task."""
        v = self.manager.vehicle(car.name)
        if not car.task_plan or car.goals is None or not v.complete or not v.goals:
            return False
        goal = self.manager.layout.node(car.goals[-1].node)
        return v.goals[-1][0] == goal and v.stops[len(v.goals) - 1] <= v.passed

    def _goal_done(self, car: _Car) -> None:
        """finish_at_goal: record the task and plan the next one from the goal."""
        self._record(car)
        car.task_plan = False
        self._next_task(car)

    def _record(self, car: _Car) -> None:
        """The vehicle's task is done (now, or when its handling there ends)."""
        assert car.goals is not None
        done = max(self.now, self.manager.vehicle(car.name).ready_at)
        self.stats.tasks.append(
            TaskRecord(
                car.name, tuple(car.goals), car.assigned, done, car.start, car.heading, car.delay
            )
        )
        self.tasks.finished(car.name, car.goals, done)
        car.goals = None

    def _route_done(self, car: _Car) -> None:
        v = self.manager.vehicle(car.name)
        finished = car.task_plan and v.complete and car.goals is not None
        if finished and not self.config.finish_at_goal:
            self._record(car)
            self._next_task(car)
        elif car.goals is not None:
            self._try_plan(car)
        elif self.manager.layout.parking and v.route[-1] not in self.manager.layout.parking:
            self._next_task(car)

    def _occupy(self, car: _Car, resources: tuple[int, ...]) -> None:
        occupant = self._occupant
        for r in car.occupied:
            occupant[r].discard(car.idx)
        cls = self.manager.vehicle(car.name).cls
        conflicts = self.manager.conflicts
        for r in resources:
            for other in conflicts.of(cls, r):
                for w in occupant.get(other, ()):
                    if w != car.idx:
                        self.stats.collisions += 1
        for r in resources:
            occupant.setdefault(r, set()).add(car.idx)
        car.occupied = resources

    def _check(self) -> None:
        """Safety net: wait-for cycles, and vehicles stuck with a stuck wait-for chain.

        A vehicle that has not moved for `stall_after` seconds while work is left is a stall
        only if the vehicle at the end of its wait-for chain has not moved for that long either
        (a long wait behind a vehicle that is driving is counted in `long_waits`).
        """
        self.stats.wait_cycles += len(self.manager.wait_cycles())
        limit = self.config.stall_after
        for car in self._cars:
            v = self.manager.vehicle(car.name)
            busy = car.goals is not None or v.passed < len(v.route) - 1
            if not busy or car.moving or car.stalled or self.now - car.last_move <= limit:
                continue
            car.stalled = True
            root = self._root(car)
            if root.moving or self.now - root.last_move <= limit:
                self.stats.long_waits += 1
            else:
                self.stats.stalls += 1
                self.stats.stall_chains.append(self._describe_chain(car))

    def _describe_chain(self, car: _Car) -> str:
        """The stalled vehicle's wait-for chain, one line per vehicle (why it does not move)."""
        lines, seen = [f"t={self.now:.0f}"], set()
        while car.name not in seen:
            seen.add(car.name)
            v = self.manager.vehicle(car.name)
            step = v.base + 1
            holds = (v.edge_holds[step], v.node_holds[step]) if step < len(v.route) else ()
            ahead = [repr(o) for h in holds if h for o in self.manager.table.blockers(h)]
            lines.append(
                f"{car.name} at {self.manager.layout.node_ids[v.route[v.passed]]} "
                f"passed {v.passed} base {v.base} route {len(v.route)} moving {car.moving} "
                f"still {self.now - car.last_move:.0f}s ready_at {v.ready_at:.0f} "
                f"goals {car.goals is not None} complete {v.complete} static {v.static} "
                f"blocked_by {v.blocked_by} ahead {ahead}"
            )
            following = self.manager.waiting_for(car.name)
            if not following:
                break
            car = self._by_name[following[0]]
        return " | ".join(lines)

    def _root(self, car: _Car) -> _Car:
        """The end of the chain of vehicles `car` waits for."""
        seen = {car.name}
        while True:
            ahead = self.manager.waiting_for(car.name)
            if not ahead or ahead[0] in seen:
                return car
            car = self._by_name[ahead[0]]
            seen.add(car.name)


def free_flow_time(
    manager: TrafficManager, vehicle_class: int, start: int, heading: int, goals: Sequence[Goal]
) -> float:
    """Seconds a vehicle alone on the layout needs for `goals` (turns and dwells included)."""
    graph: ClassGraph = manager.graphs[vehicle_class]
    targets = [(manager.layout.node(g.node), g.dwell) for g in goals]
    path = search(graph, _EMPTY.get(manager), -1, start, heading, 0.0, INF, targets)
    if path is None:
        return INF
    return path.arrive[-1] + targets[-1][1]


class _Empty:
    """Empty reservation tables, one per layout size."""

    def __init__(self) -> None:
        self._tables: dict[int, ReservationTable] = {}

    def get(self, manager: TrafficManager) -> ReservationTable:
        count = manager.layout.resource_count
        if count not in self._tables:
            self._tables[count] = ReservationTable(count)
        return self._tables[count]


_EMPTY = _Empty()
