"""Running a fleet through a scenario: tasks, the traffic run, the ghost run and the figures."""

from __future__ import annotations

import math
import random
import statistics
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

from bench.traffic.maps import GridMap
from traffic.des import SimConfig, SimStats, Simulation, Tasks, free_flow_time
from traffic.footprint import VehicleClass
from traffic.layout import Layout
from traffic.manager import TrafficManager
from traffic.plans import Goal, ReleasePolicy
from traffic.reservations import ReservationTable
from traffic.sipp import heading_key, search

VEHICLE = VehicleClass("amr", length=0.8, width=0.5, speed=1.0, rotation_speed=math.pi / 2)
HANDLING = 5.0  # s per pick and per drop
WEIGHT = 1.1  # SIPP heuristic weight: plans at most 10 % later than the earliest arrival


def node_id(cell: tuple[int, int]) -> str:
    """The layout node id of a grid cell."""
    return f"{cell[0]},{cell[1]}"


class WarehouseTasks:
    """Transport orders: a random shelf cell (pick), then a free workstation (drop).

    The pick sequence of each vehicle is fixed by the seed (the ghost run draws the same one);
    the workstation is drawn among those no other open order is heading for, as a WMS would.
    """

    def __init__(self, grid: GridMap, seed: int, vehicles: Sequence[str], *, ghost: bool = False):
        self.picks = [node_id(c) for c in grid.picks]
        self.stations = [node_id(c) for c in grid.stations]
        self._rng = {v: random.Random(seed * 7919 + i) for i, v in enumerate(vehicles)}
        self._stations = random.Random(seed)
        self._targeted: set[str] = set()
        self._untasked: dict[str, str] = {}  # vehicles still standing where they started
        self.ghost = ghost

    def standing(self, starts: dict[str, str]) -> None:
        """Vehicles standing at these nodes until their first task (their stations are taken)."""
        self._untasked = dict(starts)

    def next_goals(self, vehicle_id: str, node: str, now: float) -> list[Goal] | None:
        """Pick, then drop at a workstation."""
        pick = self._rng[vehicle_id].choice(self.picks)
        self._untasked.pop(vehicle_id, None)
        choices = self.stations
        if not self.ghost:
            taken = self._targeted | set(self._untasked.values())
            choices = [s for s in self.stations if s not in taken and s != node]
        drop = self._stations.choice(choices)
        self._targeted.add(drop)
        return [Goal(pick, HANDLING), Goal(drop, HANDLING)]

    def finished(self, vehicle_id: str, goals: Sequence[Goal], now: float) -> None:
        """The workstation is free for other orders again."""
        self._targeted.discard(goals[-1].node)

    def reassign(
        self, vehicle_id: str, goals: Sequence[Goal], node: str, now: float
    ) -> list[Goal] | None:
        """The plan to this order keeps failing: the same pick, another free workstation.

        (On S3 a drop that the plans made before pass until far ahead left first tours
        unplannable for minutes; a WMS would send such an order to another workstation.)
        """
        pick, drop = goals[0], goals[-1]
        taken = self._targeted | set(self._untasked.values())
        choices = [s for s in self.stations if s not in taken and s != node]
        if not choices:
            return None
        self._targeted.discard(drop.node)
        new = self._stations.choice(choices)
        self._targeted.add(new)
        return [pick, Goal(new, drop.dwell)]


@dataclass
class Run:
    """One traffic run and what it measured."""

    manager: TrafficManager
    stats: SimStats
    seconds: float
    wall: float
    # tasks finished plus, per task still open at the end, the share of its free-flow time
    # already covered (see `open_work`)
    work: float = 0.0
    # the simulation itself, at a cut of a long run (saved to be resumed)
    simulation: Simulation | None = None


def fleet_manager(
    layout: Layout,
    starts: Sequence[tuple[str, float]],
    *,
    policy: ReleasePolicy,
    max_expansions: int,
    weight: float = WEIGHT,
    quick_search: tuple[int, float] | None = None,
    lifelong: bool = False,
    refuge_penalty: float = 0.0,
    replan_after: float = 5.0,
    retime_slack: float = 2.0,
    retime_growth: float = 0.0,
    improve_budget: int = 0,
    improve_slack: float = 2.0,
    switch_push: float | None = None,
    congestion: tuple[float, float] | None = None,
    grid_rules: bool = False,
) -> TrafficManager:
    """A manager with vehicles `v0..` standing at `starts` (node id, heading).

    `lifelong` turns on the opt-in goal refuges and stepping aside (`traffic.aside`);
    `switch_push` (seconds, None: off) the opt-in switching (`traffic.switching`);
    `congestion` (against, through; None: off) the opt-in flow cost (`traffic.congestion`);
    `grid_rules` LoRR's cells and following (`TrafficManager(grid_rules=True)`).
    """
    manager = TrafficManager(
        layout,
        [VEHICLE],
        policy=policy,
        max_expansions=max_expansions,
        weight=weight,
        quick_search=quick_search,
        goal_refuge=lifelong,
        step_aside=lifelong,
        refuge_penalty=refuge_penalty if lifelong else 0.0,
        replan_after=replan_after,
        retime_slack=retime_slack,
        retime_growth=retime_growth,
        improve_budget=improve_budget,
        improve_slack=improve_slack,
        switching=switch_push is not None,
        switch_push=switch_push or 0.0,
        congestion=congestion,
        grid_rules=grid_rules,
    )
    for i, (node, heading) in enumerate(starts):
        manager.add_vehicle(f"v{i}", node, 0.0, heading=heading)
    return manager


def run(
    manager: TrafficManager,
    tasks: Tasks,
    seconds: float,
    config: SimConfig,
    *,
    cuts: Sequence[float] = (),
    on_cut: Callable[[Run], None] | None = None,
    resume: Simulation | None = None,
    after: float = 0.0,
    wall_before: float = 0.0,
) -> Run:
    """Execute `seconds` of simulated time; at each of `cuts` (s, before `seconds`) hand
    `on_cut` the run so far (a long run leaves its figures on the way). `resume` goes on with
    a simulation saved at the cut `after` (only later cuts follow), `wall_before` the wall
    seconds it had taken so far."""
    began = time.perf_counter() - wall_before
    simulation = resume or Simulation(manager, tasks, config)
    for cut in sorted(c for c in cuts if after < c < seconds):
        stats = simulation.run(cut)
        if on_cut is not None:
            so_far = len(stats.tasks) + open_work(manager, simulation)
            on_cut(Run(manager, stats, cut, time.perf_counter() - began, so_far, simulation))
    stats = simulation.run(seconds)
    wall = time.perf_counter() - began
    work = len(stats.tasks) + open_work(manager, simulation)
    return Run(manager, stats, seconds, wall, work)


def open_work(manager: TrafficManager, simulation: Simulation) -> float:
    """Tasks' worth of progress on the tasks still open: per task, the share of its
    free-flow time (alone on the layout) that the goals served and the node reached cover.

    With tours of 10 to 20 minutes (S3) a half-hour count of finished tasks depends on where
    the cut falls in each vehicle's tour; this is the unfinished rest (`rho_work`).
    """
    layout = manager.layout
    done = 0.0
    for name, goals, start, heading in simulation.open_tasks():
        v = manager.vehicle(name)
        if not v.goals or v.goals[-1][0] != layout.node(goals[-1].node):
            continue  # no plan for this task yet (or a detour): nothing covered
        total = free_flow_time(manager, v.cls, start, heading, goals)
        left = [
            Goal(layout.node_ids[node], dwell)
            for (node, dwell), stop in zip(v.goals, v.stops, strict=True)
            if stop > v.passed
        ]
        here = v.route[v.passed]
        rest = free_flow_time(manager, v.cls, here, v.headings[v.passed], left) if left else 0.0
        if 0 < total < math.inf and rest < math.inf:
            done += min(1.0, max(0.0, (total - rest) / total))
    return done


Tour = tuple[float, float]  # when a ghost vehicle began a task and when it finished it


def ghost(
    manager: TrafficManager,
    starts: Sequence[tuple[str, float]],
    tasks: Tasks,
    seconds: float,
    config: SimConfig,
) -> tuple[int, float]:
    """Tasks finished in `seconds` when vehicles ignore each other (same tasks and delays),
    and the work done (see `ghost_tours` and `ghost_at`)."""
    return ghost_at(ghost_tours(manager, starts, tasks, seconds, config), seconds)


def ghost_tours(
    manager: TrafficManager,
    starts: Sequence[tuple[str, float]],
    tasks: Tasks,
    seconds: float,
    config: SimConfig,
) -> list[list[Tour]]:
    """Per vehicle, the tasks it drives in `seconds` as if alone (the last one may end later).

    Every vehicle drives its own tasks from its start as if alone: free-flow routes (turns and
    handling included), the same delay probability and range per move.
    """
    layout = manager.layout
    graph = manager.graphs[0]
    empty = ReservationTable(layout.resource_count)
    tours: list[list[Tour]] = []
    for i, (start, angle) in enumerate(starts):
        name = f"v{i}"
        rng = random.Random(config.seed * 100_003 + i)
        node, heading, now = layout.node(start), heading_key(angle), 0.0
        mine: list[Tour] = []
        tours.append(mine)
        while now < seconds:
            goals = tasks.next_goals(name, layout.node_ids[node], now)
            if goals is None:
                break
            targets = [(layout.node(g.node), g.dwell) for g in goals]
            path = search(graph, empty, -1, node, heading, now, math.inf, targets)
            if path is None:
                break
            began = now
            now = path.arrive[-1] + targets[-1][1]
            for _ in range(len(path.nodes) - 1):
                if rng.random() < config.delay_probability:
                    now += rng.uniform(*config.delay_range)
            mine.append((began, now))
            tasks.finished(name, goals, now)
            node, heading = path.nodes[-1], path.headings[-1]
    return tours


def ghost_at(tours: Sequence[Sequence[Tour]], cut: float) -> tuple[int, float]:
    """The ghost's tasks finished by `cut` s and its work done: those tasks plus, for the task
    each vehicle is on at the cut, the share of its duration already spent (as `Run.work`)."""
    finished = 0
    work = 0.0
    for mine in tours:
        for began, end in mine:
            if end <= cut:
                finished += 1
                work += 1.0
            elif began < cut:
                work += (cut - began) / (end - began)
    return finished, work


def figures(result: Run, *, sample: int = 1500, seed: int = 0) -> dict[str, Any]:
    """The flat figures of a run: throughput, waiting, safety net, timings."""
    stats, manager = result.stats, result.manager
    hours = result.seconds / 3600
    tasks = stats.tasks
    rng = random.Random(seed)
    chosen = tasks if len(tasks) <= sample else rng.sample(tasks, sample)
    waits = []
    for task in chosen:
        free = free_flow_time(manager, 0, task.start, task.heading, task.goals)
        if math.isfinite(free):
            waits.append(max(0.0, task.done - task.assigned - free - task.delay))
    plan_ms = [s * 1e3 for s in stats.plan_seconds]
    release_us, release_cpu_us = stats.release_seconds, stats.release_cpu_seconds
    plan_cpu_ms = [s * 1e3 for s in stats.plan_cpu_seconds]
    tick_cpu_ms = [s * 1e3 for s in stats.replan_cpu_seconds]
    return {
        "vehicles": len(manager.vehicle_ids),
        "simulated_hours": round(hours, 3),
        "tasks_finished": len(tasks),
        "throughput_per_hour": round(len(tasks) / hours, 1) if hours else 0.0,
        "wait_per_order_mean_s": _round(statistics.fmean(waits) if waits else 0.0),
        "wait_per_order_p95_s": _round(percentile(waits, 95)),
        "decision_point_stop_mean_s": _round(statistics.fmean(stats.waits) if stats.waits else 0),
        "decision_point_stop_p95_s": _round(percentile(stats.waits, 95)),
        "deadlocks_wait_cycles": stats.wait_cycles,
        "deadlocks_stalls": stats.stalls,
        "waits_over_300s_behind_a_driving_vehicle": stats.long_waits,
        "collisions": stats.collisions,
        "plan_failures": stats.plan_failures,
        "reassigned_orders": stats.reassigned,
        "moves": stats.moves,
        "delayed_moves": stats.delays,
        "plan_ms_p50": _round(percentile(plan_ms, 50)),
        "plan_ms_p95": _round(percentile(plan_ms, 95)),
        "plan_ms_max": _round(max(plan_ms, default=0.0)),
        # histograms (1 % buckets, `traffic.des_records.Timings`): a state message each
        "release_us_p50": _round(release_us.percentile(50) * 1e6),
        "release_us_p95": _round(release_us.percentile(95) * 1e6),
        "release_us_p99": _round(release_us.percentile(99) * 1e6),
        "release_us_max": _round(release_us.max * 1e6),
        "plan_cpu_ms_p50": _round(percentile(plan_cpu_ms, 50)),
        "plan_cpu_ms_p95": _round(percentile(plan_cpu_ms, 95)),
        "plan_cpu_ms_max": _round(max(plan_cpu_ms, default=0.0)),
        "release_cpu_us_p95": _round(release_cpu_us.percentile(95) * 1e6),
        "release_cpu_us_p99": _round(release_cpu_us.percentile(99) * 1e6),
        "release_cpu_us_p99_9": _round(release_cpu_us.percentile(99.9) * 1e6),
        "release_cpu_us_max": _round(release_cpu_us.max * 1e6),
        # the target is 1 ms per state message: how many took longer (CPU, to 1 %)
        "release_cpu_over_1ms": release_cpu_us.count_over(1e-3),
        "tick_cpu_ms_p50": _round(percentile(tick_cpu_ms, 50)),
        "tick_cpu_ms_p95": _round(percentile(tick_cpu_ms, 95)),
        "ticks": len(tick_cpu_ms),
        # per simulated second, whatever the tick interval (SimConfig.tick_every)
        "tick_cpu_s_per_simulated_s": _round(sum(tick_cpu_ms) / 1e3 / max(result.seconds, 1e-9)),
        "switches": manager.switches,
        "switches_pushing_the_late_vehicle": manager.switch_pushes,
        "switch_pushes_dropped": manager.switches_dropped,
        "wall_s": _round(result.wall),
        "stall_chains": stats.stall_chains,
    }


def percentile(values: Sequence[float], q: float) -> float:
    """The sample of rank ⌊len·q/100⌋ in ascending order (0.0 for none)."""
    if not values:
        return 0.0
    ordered = sorted(values)
    return ordered[min(len(ordered) - 1, int(len(ordered) * q / 100))]


def _round(value: float) -> float:
    return round(value, 3)
