"""Energy: continuous transport orders with shared chargers, in simulated time.

A time-stepped simulation (1 s steps) of `--vehicles` vehicles on the demo warehouse with its
2 charge stations (one point each), a pending order for every vehicle at all times, and the
simulator's battery model (`simulator.config.VehicleConfig`: drain per metre driven, drain per
second standing, charge per second). Every 5 simulated seconds it takes the decisions the
system takes: the charging policy (`battery.policy.Levels`), charger assignment with queueing
(`battery.planning.assign_points`), the dispatcher's batch assignment
(`orders.assignment.plan_batch`) with the battery's job refusal from the learned consumption
(`battery.policy.Consumption`). Traffic is ignored (vehicles pass through each other).

It reports the lowest charge any vehicle reached, the most vehicles ever booked on or standing
at one charging point, and the finished orders against the same run with charging ignored
(batteries never drain): ρ for energy.
"""

import argparse
import math
import random
from dataclasses import dataclass, field
from datetime import UTC, datetime, timedelta
from typing import Any

from battery.planning import ChargePoint, ChargeRequest, assign_points
from battery.policy import Consumption, Levels, Reason
from bench import results
from maps.demo import warehouse_layout
from orders.assignment import Candidate, Job, plan_batch
from simulator.config import VehicleConfig
from traffic import RoutingGraph
from traffic.routing import GraphEdge

EPOCH = datetime(2026, 11, 23, 6, 0, tzinfo=UTC)
CYCLE = 5  # seconds between decisions (dispatch beat, charging plan)
ACTION_SECONDS = 10.0  # pick or drop
LEARN_WINDOW = 30.0  # seconds of observation per learning step (the history sampler's pace)


@dataclass
class SimVehicle:
    key: int
    node: str
    charge: float
    consumption: Consumption = field(default_factory=Consumption)
    path: list[str] = field(default_factory=list)  # nodes still to reach, next first
    edge_left: float = 0.0  # metres to the next node of `path`
    stops: list[str] = field(default_factory=list)  # pick/drop nodes still ahead on the path
    action_left: float = 0.0
    job: int | None = None
    point: ChargePoint | None = None  # booked charging point (to, at, or still on it)
    to_charge: bool = False  # driving to its point, to start charging there
    charging: bool = False
    idle_since: float = 0.0
    window: list[float] = field(default_factory=lambda: [0.0, 0.0, 0.0])  # used, m, s

    @property
    def idle(self) -> bool:
        busy = self.path or self.action_left or self.charging or self.to_charge
        return self.job is None and not busy


@dataclass
class Result:
    finished: int = 0
    min_charge: float = 100.0
    max_per_point: int = 0
    charge_sessions: int = 0
    critical_events: int = 0
    queue_max: int = 0
    refused_jobs: int = 0


def build_graph(spec: dict[str, Any]) -> RoutingGraph:
    place = {n["id"]: (n["x"], n["y"]) for n in spec["nodes"]}
    edges = [
        GraphEdge(e["id"], e["start"], e["end"], math.dist(place[e["start"]], place[e["end"]]))
        for e in spec["edges"]
    ]
    return RoutingGraph(place, edges)


def simulate(
    *,
    vehicles: int = 10,
    hours: float = 8.0,
    charging: bool = True,
    seed: int = 1,
    levels: Levels | None = None,
    battery: VehicleConfig | None = None,
) -> Result:
    """Run the fleet for `hours` of simulated time; `charging=False` ignores the battery."""
    levels = levels or Levels()
    cfg = battery or VehicleConfig(battery_charge_per_second=0.25)
    spec = warehouse_layout()
    graph = build_graph(spec)
    rng = random.Random(seed)
    picks = [s["node"] for s in spec["stations"] if s["kind"] == "PICK"]
    drops = [s["node"] for s in spec["stations"] if s["kind"] == "DROP"]
    chargers = [s["node"] for s in spec["stations"] if s["kind"] == "CHARGE"]
    points = [ChargePoint(charger=i, point=0, node=node) for i, node in enumerate(chargers)]
    aisles = [n["id"] for n in spec["nodes"] if n["id"].startswith("A")]
    fleet = [
        SimVehicle(key=k, node=rng.choice(aisles), charge=rng.uniform(40.0, 100.0))
        for k in range(vehicles)
    ]
    orders: dict[int, tuple[str, str]] = {}
    next_order = 0
    queue: dict[int, ChargeRequest] = {}
    booked: dict[ChargePoint, int] = {}
    result = Result()
    to_charger = {p.node: graph.distances_to(p.node) for p in points}

    def send(vehicle: SimVehicle, path: list[str], stops: list[str]) -> None:
        vehicle.path = path[1:]
        vehicle.stops = stops
        vehicle.edge_left = graph.path_length(path[:2]) if len(path) > 1 else 0.0
        if stops and stops[0] == path[0]:  # already at the pickup: load right away
            vehicle.stops.pop(0)
            vehicle.action_left = ACTION_SECONDS

    for second in range(int(hours * 3600)):
        if second % CYCLE == 0:
            while len(orders) < vehicles:  # continuous: always one pending order per vehicle
                orders[next_order] = (rng.choice(picks), rng.choice(drops))
                next_order += 1
            if charging:
                _charging_cycle(levels, fleet, queue, booked, points, graph, second, result)
            _dispatch(
                levels,
                fleet,
                orders,
                queue,
                booked,
                graph,
                to_charger,
                second,
                result,
                charging=charging,
                send=send,
            )
            result.queue_max = max(result.queue_max, len(queue))
        for vehicle in fleet:
            _step(vehicle, cfg, graph, orders, booked, result, charging=charging, now=second)
        if charging:
            at_point: dict[str, int] = {}
            for vehicle in fleet:
                if vehicle.charging or (
                    vehicle.point and vehicle.node == vehicle.point.node and not vehicle.path
                ):
                    at_point[vehicle.node] = at_point.get(vehicle.node, 0) + 1
            result.max_per_point = max(result.max_per_point, *at_point.values(), 0)
            result.min_charge = min(result.min_charge, *(v.charge for v in fleet))
    return result


def _charging_cycle(
    levels: Levels,
    fleet: list[SimVehicle],
    queue: dict[int, ChargeRequest],
    booked: dict[ChargePoint, int],
    points: list[ChargePoint],
    graph: RoutingGraph,
    now: int,
    result: Result,
) -> None:
    for vehicle in fleet:
        if vehicle.charging and levels.stop_charging(
            vehicle.charge, work_waiting=True, queue_waiting=bool(queue)
        ):
            vehicle.charging = False  # stays on its point (booked) until it drives away
            vehicle.idle_since = now
        reason = levels.charge_reason(
            vehicle.charge,
            idle=vehicle.idle and vehicle.point is None,
            work_waiting=True,
            drain_per_hour=vehicle.consumption.per_hour,
        )
        if reason is not None and vehicle.key not in queue:
            queue[vehicle.key] = ChargeRequest(
                vehicle.key, vehicle.node, vehicle.charge, reason, since=now
            )
            result.critical_events += reason is Reason.CRITICAL
        elif vehicle.key in queue:  # refresh where it stands and its charge
            old = queue[vehicle.key]
            queue[vehicle.key] = ChargeRequest(
                old.key, vehicle.node, vehicle.charge, old.reason, since=old.since
            )
    free = [p for p in points if p not in booked]
    plan = assign_points(list(queue.values()), free, graph.distances_to)
    for request, point, _ in plan.assigned:
        assert point not in booked, "a charging point was booked twice"
        vehicle = fleet[request.key]
        booked[point] = vehicle.key
        vehicle.point, vehicle.to_charge = point, True
        del queue[vehicle.key]
        result.charge_sessions += 1
        path = graph.shortest_path(vehicle.node, point.node)
        vehicle.path, vehicle.stops = path[1:], []
        vehicle.edge_left = graph.path_length(path[:2]) if len(path) > 1 else 0.0


def _dispatch(
    levels: Levels,
    fleet: list[SimVehicle],
    orders: dict[int, tuple[str, str]],
    queue: dict[int, ChargeRequest],
    booked: dict[ChargePoint, int],
    graph: RoutingGraph,
    to_charger: dict[str, dict[str, float]],
    now: int,
    result: Result,
    *,
    charging: bool,
    send: Any,
) -> None:
    idle = [v for v in fleet if v.idle]
    if charging:
        # Held back: queued for a charger (except opportunity charging, which yields to work)
        # and vehicles below the working minimum.
        idle = [
            v
            for v in idle
            if (v.key not in queue or queue[v.key].reason is Reason.OPPORTUNITY)
            and levels.job_refusal(v.charge, 0.0, v.consumption.per_hour) is None
        ]
    if not idle or not orders:
        return
    assigned = {o for v in fleet if v.job is not None for o in [v.job]}
    jobs = [
        Job(key=k, pickup=pick, station=pick, created=EPOCH + timedelta(seconds=k))
        for k, (pick, _) in orders.items()
        if k not in assigned
    ]
    candidates = [Candidate(v.key, v.node, EPOCH + timedelta(seconds=v.idle_since)) for v in idle]
    plan = plan_batch(jobs, candidates, graph.distances_to, now=EPOCH + timedelta(seconds=now))
    for job, candidate, _ in plan.pairs:
        vehicle = fleet[candidate.key]
        pick, drop = orders[job.key]
        route = graph.shortest_path(vehicle.node, pick) + graph.shortest_path(pick, drop)[1:]
        if charging:
            metres = graph.path_length(route) + min(
                d.get(drop, math.inf) for d in to_charger.values()
            )
            use = vehicle.consumption.project(metres=metres, standing_seconds=2 * ACTION_SECONDS)
            if levels.job_refusal(vehicle.charge, use, vehicle.consumption.per_hour):
                result.refused_jobs += 1
                continue
        queue.pop(vehicle.key, None)
        if vehicle.point is not None:  # leaving its charging point frees it
            booked.pop(vehicle.point, None)
            vehicle.point = None
        vehicle.job = job.key
        send(vehicle, route, [pick, drop])


def _step(
    vehicle: SimVehicle,
    cfg: VehicleConfig,
    graph: RoutingGraph,
    orders: dict[int, tuple[str, str]],
    booked: dict[ChargePoint, int],
    result: Result,
    *,
    charging: bool,
    now: int,
) -> None:
    metres = 0.0
    if vehicle.action_left > 0:
        vehicle.action_left -= 1.0
    elif vehicle.path:
        budget = cfg.speed
        while budget > 0 and vehicle.path:
            moved = min(budget, vehicle.edge_left)
            budget -= moved
            metres += moved
            vehicle.edge_left -= moved
            if vehicle.edge_left <= 1e-9:
                vehicle.node = vehicle.path.pop(0)
                if vehicle.path:
                    vehicle.edge_left = graph.path_length([vehicle.node, vehicle.path[0]])
                if vehicle.stops and vehicle.node == vehicle.stops[0]:
                    vehicle.stops.pop(0)
                    vehicle.action_left = ACTION_SECONDS
                    break
    elif vehicle.job is not None:
        orders.pop(vehicle.job)
        vehicle.job = None
        vehicle.idle_since = now
        result.finished += 1
    elif vehicle.to_charge and vehicle.point is not None and vehicle.node == vehicle.point.node:
        vehicle.to_charge, vehicle.charging = False, True  # arrived: startCharging
    if not charging:
        return
    before = vehicle.charge
    if vehicle.charging:
        vehicle.charge = min(100.0, vehicle.charge + cfg.battery_charge_per_second)
        vehicle.window = [0.0, 0.0, 0.0]
        return
    vehicle.charge -= cfg.battery_idle_drain_per_second + cfg.battery_drain_per_metre * metres
    vehicle.charge = max(0.0, vehicle.charge)
    window = vehicle.window
    window[0] += before - vehicle.charge
    window[1] += metres
    window[2] += 1.0
    if window[2] >= LEARN_WINDOW:
        vehicle.consumption.observe(used=window[0], metres=window[1], seconds=window[2])
        vehicle.window = [0.0, 0.0, 0.0]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--vehicles", type=int, default=10)
    parser.add_argument("--hours", type=float, default=8.0)
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument("--charge-per-second", type=float, default=0.25)
    parser.add_argument("--quick", action="store_true", help="2 simulated hours")
    args = parser.parse_args()
    hours = 2.0 if args.quick else args.hours
    battery = VehicleConfig(battery_charge_per_second=args.charge_per_second)
    levels = Levels()
    with_energy = simulate(
        vehicles=args.vehicles, hours=hours, seed=args.seed, levels=levels, battery=battery
    )
    ignored = simulate(
        vehicles=args.vehicles, hours=hours, seed=args.seed, charging=False, battery=battery
    )
    rho = with_energy.finished / ignored.finished if ignored.finished else 0.0
    figures = {
        "vehicles": args.vehicles,
        "chargers": 2,
        "hours": hours,
        "seed": args.seed,
        "drain_per_metre": battery.battery_drain_per_metre,
        "idle_drain_per_second": battery.battery_idle_drain_per_second,
        "charge_per_second": battery.battery_charge_per_second,
        "critical_level": levels.critical,
        "finished_with_charging": with_energy.finished,
        "finished_charging_ignored": ignored.finished,
        "rho_energy": round(rho, 4),
        "min_charge": round(with_energy.min_charge, 2),
        "max_vehicles_per_point": with_energy.max_per_point,
        "charge_sessions": with_energy.charge_sessions,
        "critical_requests": with_energy.critical_events,
        "longest_queue": with_energy.queue_max,
        "jobs_refused_for_battery": with_energy.refused_jobs,
    }
    for key, value in figures.items():
        print(f"{key:28} {value}")
    if not args.quick:
        print("written to", results.write("energy", figures))


if __name__ == "__main__":
    main()
