"""Dispatch: one assignment cycle of the batch planner against greedy nearest-vehicle.

Builds a warehouse grid in memory (`maps.demo.warehouse_layout`, edge lengths from the node
coordinates), puts idle vehicles on random aisle nodes and pending orders on random pick
stations, then times `orders.assignment.plan_batch` (scipy's linear_sum_assignment) and
`plan_greedy` (the loop it replaced) on the same input and compares the empty travel to the
pickups. Three scenarios: all orders of one priority (pure travel), a realistic mix of
priorities and deadlines (where the batch also weighs urgency), both priced by distance; and
`typed`, priced as dispatch does now: travel time per vehicle type (two types of different
speed and turning rate, slow cross aisles), with a quarter of the orders restricted to one
type, so empty travel is in seconds.

With `--db`, it also times whole dispatch cycles through the ORM (`dispatch_pending_orders`:
reading the orders and vehicles, planning, 200 guarded assignments with their timeline entries)
on a throw-away SQLite database, once with each planner.
"""

import argparse
import math
import random
import statistics
import time
from datetime import UTC, datetime, timedelta
from typing import Any
from unittest import mock

from bench import results
from maps.demo import warehouse_layout
from orders.assignment import Candidate, Job, Plan, plan_batch, plan_greedy
from traffic import GraphNode, RoutingGraph, VehicleProfile
from traffic.routing import GraphEdge

NOW = datetime(2026, 11, 23, 8, 0, tzinfo=UTC)


# The two vehicle types of the `typed` scenario: a quick tugger that turns slowly, a slower
# carrier that turns on the spot quickly.
TYPES = {
    "tugger": VehicleProfile(vehicle_type="tugger", max_speed=1.6, rotation_speed=0.4),
    "carrier": VehicleProfile(vehicle_type="carrier", max_speed=1.0, rotation_speed=1.2),
}
CROSS_AISLE_SPEED = 0.5  # m/s on every fifth row's edges (a busy cross aisle)


def build_graph(spec: dict[str, Any], *, speed_limits: bool = False) -> RoutingGraph:
    """The layout's routing graph with straight-line edge lengths (as `create_layout` stores);
    with `speed_limits`, the edges along every fifth row are slow."""
    place = {n["id"]: (n["x"], n["y"]) for n in spec["nodes"]}
    nodes = [GraphNode(n["id"], n["x"], n["y"]) for n in spec["nodes"]]
    edges = []
    for e in spec["edges"]:
        (x0, y0), (x1, y1) = place[e["start"]], place[e["end"]]
        slow = speed_limits and y0 == y1 and round(y0 / 3) % 5 == 0
        edges.append(
            GraphEdge(
                e["id"],
                e["start"],
                e["end"],
                math.dist((x0, y0), (x1, y1)),
                max_speed=CROSS_AISLE_SPEED if slow else None,
            )
        )
    return RoutingGraph(nodes, edges)


def typed_scenario(
    spec: dict[str, Any], vehicles: int, orders: int, seed: int
) -> tuple[list[Job], list[Candidate]]:
    """The mixed scenario with vehicle types: every other vehicle a tugger, a quarter of the
    orders for tuggers only."""
    jobs, candidates = scenario(spec, vehicles, orders, mixed=True, seed=seed)
    typed = [
        Candidate(c.key, c.node, c.idle_since, TYPES["tugger" if i % 2 else "carrier"])
        for i, c in enumerate(candidates)
    ]
    tuggers = frozenset(c.key for c in typed if c.profile == TYPES["tugger"])
    rng = random.Random(seed + 1)
    jobs = [
        Job(j.key, j.pickup, j.station, j.priority, j.deadline, j.created, tuggers)
        if rng.random() < 0.25
        else j
        for j in jobs
    ]
    return jobs, typed


def scenario(
    spec: dict[str, Any], vehicles: int, orders: int, *, mixed: bool, seed: int
) -> tuple[list[Job], list[Candidate]]:
    rng = random.Random(seed)
    picks = [s for s in spec["stations"] if s["kind"] == "PICK"]
    aisles = [n["id"] for n in spec["nodes"] if n["id"].startswith("A")]
    jobs = []
    for key in range(orders):
        station = rng.choice(picks)
        priority, deadline = 0, None
        if mixed:
            priority = rng.choices([0, 1, 5], weights=[80, 15, 5])[0]
            if rng.random() < 0.2:
                deadline = NOW + timedelta(minutes=rng.uniform(-5, 120))
        jobs.append(
            Job(
                key=key,
                pickup=station["node"],
                station=station["id"],
                priority=priority,
                deadline=deadline,
                created=NOW - timedelta(seconds=rng.uniform(0, 3600)),
            )
        )
    candidates = [
        Candidate(
            key=10_000 + n,
            node=rng.choice(aisles),
            idle_since=NOW - timedelta(seconds=rng.uniform(0, 600)),
        )
        for n in range(vehicles)
    ]
    return jobs, candidates


def timed(run: Any, repeats: int) -> tuple[Plan, float]:
    """The plan and the median wall time in milliseconds over `repeats` runs."""
    times, plan = [], None
    for _ in range(repeats):
        started = time.perf_counter()
        plan = run()
        times.append((time.perf_counter() - started) * 1000)
    assert plan is not None
    return plan, statistics.median(times)


def compare(
    graph: RoutingGraph,
    jobs: list[Job],
    candidates: list[Candidate],
    repeats: int,
    *,
    travel_time: bool = False,
) -> dict[str, float]:
    """Both planners on the same input; costs are metres, or seconds with `travel_time`."""
    if travel_time:
        costs_to: Any = graph.travel_times_to
        by_profile: Any = lambda goal, profile: graph.travel_times_to(goal, vehicle=profile)  # noqa: E731
        unit = "s"
    else:
        costs_to, by_profile, unit = graph.distances_to, None, "m"
    batch, batch_ms = timed(
        lambda: plan_batch(jobs, candidates, costs_to, now=NOW, by_profile=by_profile), repeats
    )
    greedy, greedy_ms = timed(
        lambda: plan_greedy(jobs, candidates, costs_to, by_profile=by_profile), repeats
    )
    assert len(batch.pairs) == len(greedy.pairs), "both planners serve the same number of orders"
    return {
        "assigned": len(batch.pairs),
        "batch_cycle_ms": round(batch_ms, 2),
        "greedy_cycle_ms": round(greedy_ms, 2),
        f"batch_empty_travel_{unit}": round(batch.empty_travel, 1),
        f"greedy_empty_travel_{unit}": round(greedy.empty_travel, 1),
        "empty_travel_ratio": round(batch.empty_travel / greedy.empty_travel, 4),
        f"batch_mean_to_pickup_{unit}": round(batch.empty_travel / len(batch.pairs), 2),
        f"greedy_mean_to_pickup_{unit}": round(greedy.empty_travel / len(greedy.pairs), 2),
    }


def database_cycles(spec: dict[str, Any], vehicles: int, orders: int, seed: int) -> dict[str, Any]:
    """Milliseconds of one full `dispatch_pending_orders` per planner, on a fresh SQLite file."""
    import os
    import tempfile

    directory = tempfile.mkdtemp(prefix="bench-dispatch-")
    os.environ["DATABASE_URL"] = f"sqlite:///{directory}/bench.sqlite3"
    os.environ["REDIS_URL"] = ""  # in-process stand-ins: nothing leaves this process
    os.environ.setdefault("DJANGO_SETTINGS_MODULE", "fleet.settings")
    import django

    django.setup()
    from django.core.management import call_command

    from maps.services import create_layout
    from orders.models import TransportOrder
    from orders.services import dispatch
    from robots.models import Vehicle

    call_command("migrate", verbosity=0)
    layout = create_layout(spec=spec)
    stations = {s.station_id: s for s in layout.stations.all()}
    jobs, candidates = scenario(spec, vehicles, orders, mixed=True, seed=seed)
    Vehicle.objects.bulk_create(
        Vehicle(
            manufacturer="bench",
            serial_number=f"V{c.key}",
            connection="ONLINE",
            operating_mode="AUTOMATIC",
            map_id=layout.map_id,
            last_node_id=c.node,
        )
        for c in candidates
    )
    figures: dict[str, Any] = {}
    planners = {"batch": plan_batch, "greedy": _greedy_as_batch}
    for name, planner in planners.items():
        TransportOrder.objects.all().delete()
        TransportOrder.objects.bulk_create(
            TransportOrder(
                source=stations[j.station],
                destination=stations["DROP-1"],
                priority=j.priority,
                deadline=j.deadline,
            )
            for j in jobs
        )
        with mock.patch.object(dispatch, "plan_batch", planner):
            started = time.perf_counter()
            assigned = dispatch.dispatch_pending_orders(now=NOW)
        figures[f"db_{name}_cycle_ms"] = round((time.perf_counter() - started) * 1000, 1)
        figures[f"db_{name}_assigned"] = len(assigned)
    return figures


def _greedy_as_batch(
    jobs: list[Job],
    candidates: list[Candidate],
    distances_to: Any,
    *,
    now: datetime | None = None,
    by_profile: Any = None,
) -> Plan:
    return plan_greedy(jobs, candidates, distances_to, by_profile=by_profile)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--quick", action="store_true", help="a smaller fleet, a few seconds")
    parser.add_argument("--vehicles", type=int, default=200)
    parser.add_argument("--orders", type=int, default=1000)
    parser.add_argument("--columns", type=int, default=40)
    parser.add_argument("--rows", type=int, default=20)
    parser.add_argument("--repeats", type=int, default=5)
    parser.add_argument("--seed", type=int, default=5050)
    parser.add_argument("--db", action="store_true", help="also time full cycles via the ORM")
    args = parser.parse_args()
    if args.quick:
        args.vehicles, args.orders, args.columns, args.rows, args.repeats = 50, 250, 20, 10, 3

    spec = warehouse_layout(columns=args.columns, rows=args.rows, map_id="bench")
    graph = build_graph(spec)
    figures: dict[str, Any] = {
        "vehicles": args.vehicles,
        "orders": args.orders,
        "grid": f"{args.columns}x{args.rows}",
        "nodes": len(spec["nodes"]),
        "pick_stations": sum(1 for s in spec["stations"] if s["kind"] == "PICK"),
        "repeats": args.repeats,
        "seed": args.seed,
        "quick": args.quick,
    }
    print(
        f"dispatch: {args.vehicles} idle vehicles, {args.orders} pending orders, "
        f"{args.columns}x{args.rows} grid ({figures['nodes']} nodes), median of {args.repeats}"
    )
    timed_graph = build_graph(spec, speed_limits=True)
    for name, mixed in (("uniform", False), ("mixed", True), ("typed", True)):
        if name == "typed":
            jobs, candidates = typed_scenario(spec, args.vehicles, args.orders, args.seed)
            row = compare(timed_graph, jobs, candidates, args.repeats, travel_time=True)
            unit = "s"
        else:
            jobs, candidates = scenario(
                spec, args.vehicles, args.orders, mixed=mixed, seed=args.seed
            )
            row = compare(graph, jobs, candidates, args.repeats)
            unit = "m"
        figures |= {f"{name}_{key}": value for key, value in row.items()}
        print(
            f"  {name:7}: batch {row['batch_cycle_ms']:8.1f} ms/cycle, "
            f"empty travel {row[f'batch_empty_travel_{unit}']:9.1f} {unit} | greedy "
            f"{row['greedy_cycle_ms']:8.1f} ms/cycle, "
            f"{row[f'greedy_empty_travel_{unit}']:9.1f} {unit} | "
            f"batch/greedy travel {row['empty_travel_ratio']:.3f} ({row['assigned']} assigned)"
        )
    if args.db:
        db = database_cycles(spec, args.vehicles, args.orders, args.seed)
        figures |= db
        print(
            f"  full cycle via the ORM (SQLite, mixed): batch {db['db_batch_cycle_ms']:.0f} ms, "
            f"greedy {db['db_greedy_cycle_ms']:.0f} ms ({db['db_batch_assigned']} assigned)"
        )
    path = results.write("dispatch", figures)
    print(f"wrote {path}")


if __name__ == "__main__":
    main()
