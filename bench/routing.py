"""Routing on a large site: LIF import time, then quickest routes between random stations.

A generated warehouse of about 5,000 nodes (an aisle grid with stations on spurs, one vehicle type
with LIF properties on every node and edge) is imported as a LIF file through the real importer
into a throwaway database (Django's test database for the configured DATABASE_URL: PostgreSQL
when set). Then, in the same run, routes between random stations are timed three ways: a fresh
travel-time Dijkstra (edge-expanded graph with turning costs), a walk down the cached distance
table of the goal, and the plain distance Dijkstra on the node graph as a floor. Targets: import
under 10 s, fresh route median under 20 ms.

    python -m bench.routing [--quick] [--database-url URL]
"""

import argparse
import json
import os
import random
import statistics
import time
from collections.abc import Callable
from functools import partial
from typing import Any

SPACING = 3.0  # m between aisle nodes
SPUR = 2.0  # m from an aisle node to its station
VEHICLE_TYPE = "bench.AGV"


def warehouse_lif(columns: int, rows: int) -> dict[str, Any]:
    """A LIF file: `columns` × `rows` two-way aisle grid, a station spur at every edge node."""
    nodes: list[dict[str, Any]] = []
    edges: list[dict[str, Any]] = []
    stations: list[dict[str, Any]] = []
    props = [{"vehicleTypeId": VEHICLE_TYPE}]

    def node(node_id: str, x: float, y: float) -> None:
        nodes.append(
            {
                "nodeId": node_id,
                "mapId": "bench",
                "nodePosition": {"x": x, "y": y},
                "vehicleTypeNodeProperties": props,
            }
        )

    def two_way(a: str, b: str) -> None:
        for start, end in ((a, b), (b, a)):
            edges.append(
                {
                    "edgeId": f"{start}-{end}",
                    "startNodeId": start,
                    "endNodeId": end,
                    "vehicleTypeEdgeProperties": [
                        {"vehicleTypeId": VEHICLE_TYPE, "rotationAllowed": False, "maxSpeed": 1.5}
                    ],
                }
            )

    for c in range(columns):
        for r in range(rows):
            node(f"A{c}.{r}", c * SPACING, r * SPACING)
            if c:
                two_way(f"A{c - 1}.{r}", f"A{c}.{r}")
            if r:
                two_way(f"A{c}.{r - 1}", f"A{c}.{r}")

    def spur(side: str, aisle: str, x: float, y: float) -> None:
        station = f"{side}-{aisle}"
        node(station, x, y)
        two_way(aisle, station)
        stations.append({"stationId": station, "interactionNodeIds": [station]})

    for c in range(columns):
        spur("S", f"A{c}.0", c * SPACING, -SPUR)
        spur("N", f"A{c}.{rows - 1}", c * SPACING, (rows - 1) * SPACING + SPUR)
    for r in range(rows):
        spur("W", f"A0.{r}", -SPUR, r * SPACING)
        spur("E", f"A{columns - 1}.{r}", (columns - 1) * SPACING + SPUR, r * SPACING)
    layout = {
        "layoutId": "bench",
        "layoutName": "Routing benchmark",
        "layoutVersion": "1",
        "nodes": nodes,
        "edges": edges,
        "stations": stations,
    }
    meta = {
        "projectIdentification": "bench",
        "creator": "bench.routing",
        "exportTimestamp": "2026-11-23T00:00:00.00Z",
        "lifVersion": "1.0.0",
    }
    return {"metaInformation": meta, "layouts": [layout]}


def timed(function: Callable[[], Any]) -> tuple[float, Any]:
    start = time.perf_counter()
    result = function()
    return time.perf_counter() - start, result


def percentiles(seconds: list[float]) -> tuple[float, float]:
    """(p50, p95) in milliseconds."""
    ordered = sorted(seconds)
    return (
        statistics.median(ordered) * 1e3,
        ordered[min(len(ordered) - 1, round(0.95 * (len(ordered) - 1)))] * 1e3,
    )


def run(columns: int, rows: int, queries: int, seed: int) -> dict[str, Any]:
    from maps.models import Site, Station, VehicleType
    from maps.selectors import load_site_graph, validate_layout, vehicle_profile
    from maps.services import import_lif

    source = json.dumps(warehouse_lif(columns, rows)).encode()
    import_seconds, report = timed(lambda: import_lif(source=source, site_id="bench"))
    if not report.ok:
        raise SystemExit("\n".join(report.lines()))
    site = Site.objects.get(site_id="bench")
    VehicleType.objects.filter(type_id=VEHICLE_TYPE).update(max_speed=1.2, rotation_speed=0.8)
    load_seconds, graph = timed(lambda: load_site_graph(site=site))
    profile = vehicle_profile(vehicle_type=VehicleType.objects.get(type_id=VEHICLE_TYPE))
    expand_seconds, _ = timed(lambda: graph.for_vehicle(profile))
    validate_seconds, findings = timed(lambda: validate_layout(map=site.maps.get()))

    rng = random.Random(seed)
    station_nodes = list(
        Station.objects.filter(map__site=site).values_list("node__node_id", flat=True)
    )
    goals = rng.sample(station_nodes, max(1, queries // 10))
    pairs = [(rng.choice(station_nodes), rng.choice(goals)) for _ in range(queries)]
    pairs = [(a, b) for a, b in pairs if a != b]

    fresh, fresh_routes = [], []
    for a, b in pairs:
        seconds, route = timed(partial(graph.route, a, b, vehicle=profile))
        fresh.append(seconds)
        fresh_routes.append(route)
    distance = [timed(partial(graph.shortest_path, a, b))[0] for a, b in pairs]
    tables = [timed(partial(graph.travel_times_to, g, vehicle=profile))[0] for g in goals]
    cached, mismatches = [], 0
    for (a, b), route in zip(pairs, fresh_routes, strict=True):
        seconds, looked_up = timed(partial(graph.route_from_table, a, b, vehicle=profile))
        cached.append(seconds)
        mismatches += abs(looked_up.travel_time - route.travel_time) > 1e-6
    alternatives = [
        timed(partial(graph.routes, a, b, 3, vehicle=profile))[0] for a, b in pairs[:20]
    ]

    fresh_p50, fresh_p95 = percentiles(fresh)
    cached_p50, cached_p95 = percentiles(cached)
    distance_p50, _ = percentiles(distance)
    table_p50, _ = percentiles(tables)
    k3_p50, _ = percentiles(alternatives)
    return {
        "nodes": report.counts["nodes"],
        "edges": report.counts["edges"],
        "stations": report.counts["stations"],
        "queries": len(pairs),
        "import_s": round(import_seconds, 3),
        "graph_load_s": round(load_seconds, 3),
        "expanded_graph_build_s": round(expand_seconds, 3),
        "validate_s": round(validate_seconds, 3),
        "validation_findings": len(findings),
        "fresh_route_p50_ms": round(fresh_p50, 3),
        "fresh_route_p95_ms": round(fresh_p95, 3),
        "cached_route_p50_ms": round(cached_p50, 3),
        "cached_route_p95_ms": round(cached_p95, 3),
        "cached_speedup_p50": round(fresh_p50 / cached_p50, 1) if cached_p50 else None,
        "distance_dijkstra_p50_ms": round(distance_p50, 3),
        "table_build_p50_ms": round(table_p50, 3),
        "k3_alternatives_p50_ms": round(k3_p50, 3),
        "cached_mismatches": mismatches,
        "mean_route_nodes": round(statistics.mean(len(r.nodes) for r in fresh_routes), 1),
        "import_under_10s": import_seconds < 10.0,
        "fresh_p50_under_20ms": fresh_p50 < 20.0,
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="small layout, fewer queries")
    parser.add_argument("--database-url", help="database server to create the test database on")
    parser.add_argument("--seed", type=int, default=5050)
    args = parser.parse_args()
    if args.database_url:
        os.environ["DATABASE_URL"] = args.database_url
    os.environ.setdefault("DJANGO_SETTINGS_MODULE", "fleet.settings")
    import django
    from django.db import connection
    from django.test.utils import setup_databases, teardown_databases

    django.setup()
    columns, rows, queries = (40, 20, 100) if args.quick else (100, 47, 400)
    old = setup_databases(verbosity=0, interactive=False)
    try:
        print(f"database: {connection.vendor} ({connection.settings_dict['NAME']})")
        figures = run(columns, rows, queries, args.seed)
    finally:
        teardown_databases(old, verbosity=0)
    figures |= {"quick": args.quick, "database": connection.vendor, "seed": args.seed}
    counts = f"{figures['nodes']} nodes, {figures['edges']} edges, {figures['stations']} stations"
    print(f"layout: {counts}")
    print(f"LIF import (parse + checks + database): {figures['import_s']:.2f} s (target < 10 s)")
    print(
        f"graph from the database: {figures['graph_load_s']:.2f} s; "
        f"travel-time graph for the vehicle type: {figures['expanded_graph_build_s']:.2f} s"
    )
    print(f"validation: {figures['validate_s']:.2f} s, {figures['validation_findings']} findings")
    print(
        f"fresh route (travel time, turns), {figures['queries']} station pairs: "
        f"p50 {figures['fresh_route_p50_ms']:.2f} ms, p95 {figures['fresh_route_p95_ms']:.2f} ms "
        "(target p50 < 20 ms)"
    )
    print(
        f"cached distance-table route: p50 {figures['cached_route_p50_ms']:.3f} ms, "
        f"p95 {figures['cached_route_p95_ms']:.3f} ms ({figures['cached_speedup_p50']}× faster; "
        f"table build p50 {figures['table_build_p50_ms']:.1f} ms; "
        f"{figures['cached_mismatches']} cost mismatches)"
    )
    print(
        "distance-only Dijkstra on the node graph: "
        f"p50 {figures['distance_dijkstra_p50_ms']:.2f} ms; "
        f"3 alternatives: p50 {figures['k3_alternatives_p50_ms']:.1f} ms"
    )
    from bench import results

    print(f"wrote {results.write('routing', figures)}")


if __name__ == "__main__":
    main()
