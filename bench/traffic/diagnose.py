"""S3 diagnosis runs of the ninth round (docs/TRAFFIC_RESULTS.md).

python -m bench.traffic.diagnose wave [--fallback 2] [--vehicles 1000]
    every first order planned at t = 0, nothing driven: planned wait over free flow
python -m bench.traffic.diagnose run --seconds 300 [--budget 2] [--after 5]
        [--fallback 2] [--growth 0] [--switch-push 10]
    a short run: finished tasks and work done against the ghost's, stops, timings, and the
    stop time by what the vehicle waited for (sixteenth round)
"""

from __future__ import annotations

import argparse
import random
import statistics
import time
from typing import Any

from bench.traffic.fleet import (
    WarehouseTasks,
    fleet_manager,
    ghost,
    node_id,
    open_work,
    percentile,
)
from bench.traffic.maps import warehouse
from bench.traffic.scenarios import REASSIGN_AFTER, S3_POLICY, S3_QUICK_SEARCH
from traffic.des import SimConfig, Simulation, free_flow_time
from traffic.layout import Layout
from traffic.manager import NoPlanError, TrafficManager


def _setup(
    vehicles: int, fallback: float | None, switch_push: float | None = None
) -> tuple[TrafficManager, WarehouseTasks, list[tuple[str, float]]]:
    grid = warehouse(block_cols=36, block_rows=45, margin=51, station_cols=8)
    layout = Layout.grid(grid.free, parking=grid.stations)
    rng = random.Random(1)
    starts = [(node_id(c), 0.0) for c in rng.sample(list(grid.stations), vehicles)]
    quick = None if fallback is None else (S3_QUICK_SEARCH[0], fallback)  # S3's expansions
    m = fleet_manager(
        layout,
        starts,
        policy=S3_POLICY,
        max_expansions=150_000,
        quick_search=quick,
        switch_push=switch_push,
    )
    tasks = WarehouseTasks(grid, 1, m.vehicle_ids)
    tasks.standing({f"v{i}": node for i, (node, _) in enumerate(starts)})
    return m, tasks, starts


def wave(vehicles: int, fallback: float | None) -> None:
    """Plan every vehicle's first order at t = 0 and compare with free flow."""
    m, tasks, starts = _setup(vehicles, fallback)
    waits: list[float] = []
    cpu: list[float] = []
    fails = 0
    for i, name in enumerate(m.vehicle_ids):
        goals = tasks.next_goals(name, starts[i][0], 0.0)
        assert goals is not None
        began = time.process_time()
        try:
            plan = m.plan(name, goals, 0.0)
        except NoPlanError:
            fails += 1
            continue
        cpu.append(time.process_time() - began)
        v = m.vehicle(name)
        free = free_flow_time(m, 0, m.layout.node(starts[i][0]), v.headings[0], goals)
        waits.append(plan.arrive[-1] + goals[-1].dwell - free)
    print(
        f"planned wait mean {statistics.fmean(waits):.1f} median {statistics.median(waits):.1f}"
        f" p95 {percentile(waits, 95):.1f} s; failed {fails}; plan CPU p50 "
        f"{percentile(cpu, 50) * 1e3:.1f} p95 {percentile(cpu, 95) * 1e3:.1f} ms"
    )


class StopCauses(Simulation):
    """Adds up the time vehicles stop at their decision point by what the vehicle they wait
    for is doing when the stop begins (the manager's view: `Vehicle.blocked_by`)."""

    def __init__(self, *args: Any) -> None:
        super().__init__(*args)
        self.causes: dict[str, float] = {}
        self._cause: dict[int, str] = {}

    def _depart(self, car: Any) -> None:
        waiting = car.waiting_since >= 0
        super()._depart(car)
        if not waiting and car.waiting_since >= 0:
            self._cause[car.idx] = self._blocker_state(car.name)

    def _stop_waiting(self, car: Any) -> None:
        if car.waiting_since >= 0:
            cause = self._cause.pop(car.idx, "unknown")
            self.causes[cause] = self.causes.get(cause, 0.0) + self.now - car.waiting_since
        super()._stop_waiting(car)

    def _blocker_state(self, name: str) -> str:
        m = self.manager
        v = m.vehicle(name)
        if v.blocked_by < 0:
            return "nobody (own stay)"
        b = m.vehicle(m.vehicle_ids[v.blocked_by])
        if b.passed >= len(b.route) - 1:
            return "a vehicle at its route end"
        if b.base > b.passed:  # driving: late when its move (turn included, at most 2 s)
            # has taken over 3 s longer than the drive: an injected delay (5 to 30 s)
            travel = m.graphs[b.cls].travel[(b.route[b.passed], b.route[b.passed + 1])]
            late = self.now - b.last_progress > travel + 3.0
            return "a vehicle late on its move (delay)" if late else "a vehicle driving"
        if b.blocked_by >= 0:
            return "a vehicle waiting itself (queue)"
        return "a vehicle standing (turn, handling)"


def run(args: argparse.Namespace) -> None:
    """A short run with a breakdown."""
    m, tasks, starts = _setup(args.vehicles, args.fallback, args.switch_push or None)
    m.replan_after, m.retime_growth = args.after, args.growth
    config = SimConfig(
        seed=1, retry_backoff=2.0, reassign_after=REASSIGN_AFTER, replan_budget=args.budget
    )
    began = time.perf_counter()
    sim = StopCauses(m, tasks, config)
    stats = sim.run(args.seconds)
    wall = time.perf_counter() - began
    work = len(stats.tasks) + open_work(m, sim)
    ghost_tasks = WarehouseTasks(
        warehouse(block_cols=36, block_rows=45, margin=51, station_cols=8),
        1,
        m.vehicle_ids,
        ghost=True,
    )
    finished, ghost_work = ghost(m, starts, ghost_tasks, args.seconds, config)
    stops = stats.waits
    print(
        f"tasks {len(stats.tasks)} (ghost {finished}); work {work:.1f} (ghost "
        f"{ghost_work:.1f}): rho_work {work / ghost_work:.3f}; moves {stats.moves}; stopped "
        f"{sum(stops) / args.vehicles:.0f} s per vehicle, {len(stops)} stops; collisions "
        f"{stats.collisions}, wait cycles {stats.wait_cycles}, stalls {stats.stalls}; plan CPU"
        f" p95 {percentile(stats.plan_cpu_seconds, 95) * 1e3:.1f} ms; tick CPU p50 "
        f"{percentile(stats.replan_cpu_seconds, 50) * 1e3:.0f} ms; {wall:.0f} s wall"
    )
    total = sum(sim.causes.values()) or 1.0
    for cause, seconds in sorted(sim.causes.items(), key=lambda item: -item[1]):
        print(f"  stopped behind {cause}: {seconds:.0f} s ({seconds / total:.0%})")


def main() -> None:
    parser = argparse.ArgumentParser(description="S3 diagnosis (ninth round)")
    parser.add_argument("what", choices=["wave", "run"])
    parser.add_argument("--vehicles", type=int, default=1000)
    parser.add_argument("--seconds", type=float, default=300.0)
    parser.add_argument("--budget", type=int, default=2, help="re-plans per tick")
    parser.add_argument("--after", type=float, default=5.0, help="s waiting before a re-plan")
    parser.add_argument("--fallback", type=float, default=2.0, help="0: no bounded search")
    parser.add_argument("--growth", type=float, default=0.0, help="retime_growth")
    parser.add_argument("--switch-push", type=float, default=0.0, help="switching (0: off)")
    args = parser.parse_args()
    args.fallback = args.fallback or None
    if args.what == "wave":
        wave(args.vehicles, args.fallback)
    else:
        run(args)


if __name__ == "__main__":
    main()
