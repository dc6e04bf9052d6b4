"""Distance tables of travel-time routing (scipy's csgraph) against a reference Dijkstra.

The tables are a reverse Dijkstra on a sparse matrix: zero-weight transitions (free turns,
arrival without a heading to hold) must count as edges, and of two parallel transitions the
cheaper one must win (a sparse matrix would add them up)."""

import heapq
import math
import random

import pytest

from traffic import GraphEdge, GraphNode, RoutingGraph
from traffic import VehicleProfile as Profile

TURNING = Profile(max_speed=1.5, rotation_speed=math.pi / 4)
FREE_TURNS = Profile(max_speed=1.0)


def _grid(seed: int) -> RoutingGraph:
    """A 6 × 5 grid with random gaps, parallel edges of different lengths and held headings."""
    rng = random.Random(seed)
    nodes = {
        f"n{x}.{y}": GraphNode(
            f"n{x}.{y}", x * 3.0, y * 3.0, "m", theta=rng.choice([None, None, 0.0, math.pi / 2])
        )
        for x in range(6)
        for y in range(5)
    }
    edges: list[GraphEdge] = []

    def link(a: str, b: str, suffix: str = "", stretch: float = 1.0) -> None:
        length = math.dist((nodes[a].x, nodes[a].y), (nodes[b].x, nodes[b].y)) * stretch
        edges.append(GraphEdge(f"{a}-{b}{suffix}", a, b, length))

    for x in range(6):
        for y in range(5):
            for a, b in ((f"n{x}.{y}", f"n{x + 1}.{y}"), (f"n{x}.{y}", f"n{x}.{y + 1}")):
                if b not in nodes or rng.random() < 0.15:
                    continue
                link(a, b)
                if rng.random() < 0.8:
                    link(b, a)
                if rng.random() < 0.2:
                    link(a, b, "-long", stretch=1.7)  # parallel: the table keeps the cheaper
    return RoutingGraph(nodes.values(), edges)


def _reference(graph: RoutingGraph, profile: Profile, goal: str) -> list[float]:
    """Plain Dijkstra backwards over the time graph's transitions."""
    timegraph = graph.for_vehicle(profile)
    into: dict[int, list[tuple[int, float]]] = {}
    for source, target, w in timegraph._graph.weighted_edge_list():
        into.setdefault(target, []).append((source, timegraph._weights[w]))
    distance = [math.inf] * timegraph._graph.num_nodes()
    start = timegraph._arrive[goal]
    distance[start] = 0.0
    queue = [(0.0, start)]
    while queue:
        seconds, state = heapq.heappop(queue)
        if seconds > distance[state]:
            continue
        for source, weight in into.get(state, []):
            if seconds + weight < distance[source]:
                distance[source] = seconds + weight
                heapq.heappush(queue, (seconds + weight, source))
    return distance


@pytest.mark.parametrize("seed", [1, 2, 3])
@pytest.mark.parametrize("profile", [TURNING, FREE_TURNS], ids=["turning", "free-turns"])
def test_tables_match_a_reference_dijkstra(seed: int, profile: Profile) -> None:
    graph = _grid(seed)
    timegraph = graph.for_vehicle(profile)
    weights = timegraph._weights
    assert any(w == 0.0 for w in weights)  # zero-weight transitions are part of the test
    for goal in ("n0.0", "n3.2", "n5.4", "n2.4"):
        table = list(timegraph._table(goal))
        expected = _reference(graph, profile, goal)
        assert [math.isinf(t) for t in table] == [math.isinf(e) for e in expected]
        assert [t for t in table if not math.isinf(t)] == pytest.approx(
            [e for e in expected if not math.isinf(e)], abs=1e-9
        )


def test_the_cheaper_of_two_parallel_edges_sets_the_travel_time() -> None:
    a, b = GraphNode("a", 0, 0, "m"), GraphNode("b", 10, 0, "m")
    edges = [GraphEdge("slow", "a", "b", 30.0), GraphEdge("fast", "a", "b", 10.0)]
    graph = RoutingGraph([a, b], edges)

    assert graph.travel_times_to("b", vehicle=FREE_TURNS)["a"] == pytest.approx(10.0)
    assert graph.route_from_table("a", "b", vehicle=FREE_TURNS).edges == ["fast"]
