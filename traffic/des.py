"""A discrete-event execution of traffic plans, faster than real time (tests and benchmarks).

Vehicles drive only what the manager released: one step at a time (turn on the spot, drive the
edge), optionally delayed at random, and report each node reached with `on_progress` (under
grid rules also each node left, `on_leave`, after the turn and any delay: a delay is a stay).
When a vehicle ends its route it gets its next task from a `Tasks` source. Independently of
the manager's bookkeeping it counts collisions, wait-for cycles and stalls (`traffic.des_watch`).
What a run is given and measures is in `traffic.des_records`, the free-flow time that ratios
are measured against in `traffic.free_flow`.
"""

from __future__ import annotations

import heapq
import random
import time
from collections.abc import Sequence
from typing import cast

from traffic.des_records import ReassigningTasks, SimConfig, SimStats, TaskRecord, Tasks
from traffic.des_watch import Occupancy, StallWatch
from traffic.free_flow import free_flow_time
from traffic.manager import NoPlanError, TrafficManager
from traffic.plans import Goal, Plan, Release

MOVE, RETRY, CHECK, LEAVE = 0, 1, 2, 3


class _Car:
    """One simulated vehicle: what it physically does and which task it serves."""

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
        "failures",
        "next_try",
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
        self.failures = 0  # plans that failed in a row (retries back off)
        self.next_try = 0.0  # retry_on_the_way: no new try on the way before


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
        self._bodies = Occupancy(manager.conflicts)
        self._watch = StallWatch(manager, self._cars, self.stats, config.stall_after)
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
            elif kind == LEAVE:
                self._leave(self._cars[idx])
            elif idx == -1:
                self._watch.check(self.now)
                self._push(self.now + self.config.check_every, CHECK, -1)
            else:
                self._tick()
                self._push(self.now + self.config.tick_every, CHECK, -2)
        self.now = until
        return self.stats

    def open_tasks(self) -> list[tuple[str, tuple[Goal, ...], int, int]]:
        """Tasks in progress: (vehicle id, goals, node and heading where it was assigned)."""
        return [
            (car.name, tuple(car.goals), car.start, car.heading)
            for car in self._cars
            if car.goals is not None
        ]

    def _push(self, at: float, kind: int, idx: int) -> None:
        self._seq += 1
        heapq.heappush(self._events, (at, self._seq, kind, idx))

    def _tick(self) -> None:
        """The manager's housekeeping; a re-plan in it may end a route where a vehicle stands.

        That happens when the re-plan serves the last goal at the decision point (the old route
        passed the goal, stepped aside and came back): the manager returns a release with
        `base_end == route_end` for it, and the vehicle's task is done there.
        """
        cpu = time.process_time()
        releases = self.manager.tick(self.now, budget=self.config.replan_budget)
        self.stats.replan_cpu_seconds.append(time.process_time() - cpu)
        self._apply(releases)
        for release in releases:
            car = self._by_name[release.vehicle_id]
            v = self.manager.vehicle(car.name)
            ended = release.base_end == release.route_end == v.passed == len(v.route) - 1
            if ended and release.plan_id == v.plan_id and not car.moving:
                self._stop_waiting(car)
                self._settle(car)

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
        if not self._plan_task(car):
            self._fallback(car)

    def _plan_task(self, car: _Car) -> bool:
        """Plan the car's task from where it stands (timed) and start it; False if no plan."""
        assert car.goals is not None
        began, cpu = time.perf_counter(), time.process_time()
        try:
            plan = self.manager.plan(car.name, car.goals, self.now)
        except NoPlanError as failed:
            self.stats.plan_failures += 1
            self._apply(failed.releases)  # vehicles sent aside on the way
            return False
        self.stats.plan_seconds.append(time.perf_counter() - began)
        self.stats.plan_cpu_seconds.append(time.process_time() - cpu)
        car.failures = 0
        car.task_plan = True
        self._started(car, plan)
        return True

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
        if self._reassign(car):
            self._push(self.now + self.config.retry_after, RETRY, car.idx)
            return
        self._push(self.now + self._retry_delay(car), RETRY, car.idx)

    def _reassign(self, car: _Car) -> bool:
        """After `reassign_after` failed plans in a row, ask the task source for other goals.

        Only for a task not started yet (the vehicle stands where it got it): a drop held
        far ahead by the plans made before can leave a vehicle's first tour unplannable for
        minutes, which no retry schedule fixes (S3).
        """
        after = self.config.reassign_after
        if not after or not hasattr(self.tasks, "reassign") or car.goals is None:
            return False
        if car.failures + 1 < after:
            return False
        v = self.manager.vehicle(car.name)
        node = v.route[v.passed]
        if node != car.start or v.passed != len(v.route) - 1:
            return False
        source = cast(ReassigningTasks, self.tasks)
        goals = source.reassign(car.name, car.goals, self.manager.layout.node_ids[node], self.now)
        if goals is None:
            return False
        car.goals = goals
        car.failures = 0
        self.stats.reassigned += 1
        return True

    def _retry_delay(self, car: _Car) -> float:
        """Seconds until the next try: `retry_after`, times `retry_backoff` per failure in a row
        (a goal held far ahead fails the same costly search again and again), at most
        `retry_max`."""
        delay = self.config.retry_after * self.config.retry_backoff**car.failures
        car.failures += 1
        return min(delay, self.config.retry_max)

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
        self._stop_waiting(car)
        graph = manager.graphs[v.cls]
        u, n = v.route[p], v.route[p + 1]
        before = max(0.0, v.ready_at - self.now) + graph.turn(v.headings[p], v.headings[p + 1])
        config = self.config
        if car.rng.random() < config.delay_probability:
            extra = car.rng.uniform(*config.delay_range)
            before += extra
            car.delay += extra
            self.stats.delays += 1
        car.moving = True
        self.stats.moves += 1
        if manager.leave < 0:  # footprint rules: u stays occupied until n is reached
            edge = v.edge_holds[p + 1]
            assert edge is not None  # every step after the first has its segment hold
            self._occupy(car, (u, edge.resource, n))
            self._push(self.now + before + graph.travel[(u, n)], MOVE, car.idx)
        elif before > 0:  # grid rules: u is left when the drive starts, after the turn
            self._push(self.now + before, LEAVE, car.idx)
        else:
            self._leave(car)

    def _leave(self, car: _Car) -> None:
        """Grid rules: the vehicle drives off its node (a delay, as any stay, came before)."""
        v = self.manager.vehicle(car.name)
        u, n, edge = v.route[v.passed], v.route[v.passed + 1], v.edge_holds[v.passed + 1]
        assert edge is not None
        self._occupy(car, (edge.resource, n))
        self._push(self.now + self.manager.graphs[v.cls].travel[(u, n)], MOVE, car.idx)
        self._apply(self.manager.on_leave(car.name, self.now))

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
        self._settle(car)

    def _settle(self, car: _Car) -> None:
        """The vehicle stands at a node: its task or route may be done, or it drives on."""
        v = self.manager.vehicle(car.name)
        if self.config.finish_at_goal and self._at_goal(car):
            self._goal_done(car)
            v = self.manager.vehicle(car.name)
            if not car.moving and v.passed < len(v.route) - 1:
                self._depart(car)
        elif v.passed == len(v.route) - 1:
            self._route_done(car)
        elif not car.moving:
            if self._on_the_way(car) and car.moving:
                return
            self._depart(car)

    def _on_the_way(self, car: _Car) -> bool:
        """retry_on_the_way: a vehicle standing at a node on a route that does not serve its
        task (waiting for its base) plans the task from there; True if it got a plan."""
        if (
            not self.config.retry_on_the_way
            or car.goals is None
            or car.task_plan
            or self.now < car.next_try
        ):
            return False
        car.next_try = self.now + self.config.retry_after
        return self._plan_task(car)

    def _stop_waiting(self, car: _Car) -> None:
        """The vehicle's stop at its decision point is over: record how long it was."""
        if car.waiting_since >= 0:
            self.stats.waits.append(self.now - car.waiting_since)
            car.waiting_since = -1.0

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
        cls = self.manager.vehicle(car.name).cls
        self.stats.collisions += self._bodies.move(car.idx, cls, car.occupied, resources)
        car.occupied = resources


__all__ = [
    "SimConfig",
    "SimStats",
    "Simulation",
    "TaskRecord",
    "Tasks",
    "free_flow_time",
]
