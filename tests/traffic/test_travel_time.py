"""Travel-time routing: speeds, turning, LIF vehicle-type rules, alternatives, tables, floors."""

import math

import pytest

from traffic import EdgeRule, GraphEdge, GraphNode, NodeRule, NoRouteError, RoutingGraph
from traffic import VehicleProfile as Profile

T1 = Profile(vehicle_type="T1", max_speed=2.0, rotation_speed=math.pi / 2)  # a quarter turn: 1 s


def node(node_id: str, x: float, y: float, map_id: str = "m", **kwargs) -> GraphNode:
    return GraphNode(node_id, x, y, map_id, **kwargs)


def edge(a: GraphNode, b: GraphNode, **kwargs) -> GraphEdge:
    return GraphEdge(
        f"{a.node_id}-{b.node_id}",
        a.node_id,
        b.node_id,
        math.dist((a.x, a.y), (b.x, b.y)),
        **kwargs,
    )


def two_way(a: GraphNode, b: GraphNode, **kwargs) -> list[GraphEdge]:
    return [edge(a, b, **kwargs), edge(b, a, **kwargs)]


def corner(**rule) -> tuple[RoutingGraph, dict[str, GraphNode]]:
    """a(0,0) → b(10,0) → c(10,10): one left turn at b; every element has rules for T1."""
    rules = {"T1": EdgeRule(**rule)}
    nodes = {
        n: node(n, x, y, rules={"T1": NodeRule()})
        for n, x, y in [("a", 0, 0), ("b", 10, 0), ("c", 10, 10)]
    }
    edges = [edge(nodes["a"], nodes["b"], rules=rules), edge(nodes["b"], nodes["c"], rules=rules)]
    return RoutingGraph(nodes.values(), edges), nodes


def test_travel_time_uses_the_lowest_speed_limit_and_pays_for_turns() -> None:
    graph, _ = corner(max_speed=1.0)

    route = graph.route("a", "c", vehicle=T1)

    assert route.nodes == ["a", "b", "c"]
    assert route.edges == ["a-b", "b-c"]
    assert route.length == pytest.approx(20.0)
    assert route.travel_time == pytest.approx(20.0 / 1.0 + 1.0)  # edge limit 1 m/s, one 90° turn


def test_the_vehicle_speed_limits_when_the_edge_allows_more() -> None:
    graph, _ = corner(max_speed=5.0)

    assert graph.route("a", "c", vehicle=T1).travel_time == pytest.approx(20.0 / 2.0 + 1.0)


def test_turns_cost_nothing_without_a_rotation_speed() -> None:
    graph, _ = corner()

    route = graph.route("a", "c", vehicle=Profile(vehicle_type="T1", max_speed=2.0))

    assert route.travel_time == pytest.approx(10.0)


def test_a_forbidden_turn_at_a_node_leaves_no_route() -> None:
    graph, _ = corner(rotation_at_start="NONE")

    with pytest.raises(NoRouteError):
        graph.route("a", "c", vehicle=T1)


def test_clockwise_only_makes_a_left_turn_the_long_way_round() -> None:
    graph, _ = corner(rotation_at_start="CW", rotation_at_end="CW")

    route = graph.route("a", "c", vehicle=T1)

    assert route.travel_time == pytest.approx(10.0 + 3.0)  # 270° clockwise at 90°/s


def test_rotation_allowed_on_the_edge_saves_the_turn_on_the_spot() -> None:
    graph, _ = corner(rotation_allowed=True)

    assert graph.route("a", "c", vehicle=T1).travel_time == pytest.approx(10.0)


def test_driving_backwards_on_one_edge_costs_a_half_turn() -> None:
    a, b, c = node("a", 0, 0), node("b", 10, 0), node("c", 20, 0)
    forwards = {"T1": EdgeRule()}
    backwards = {"T1": EdgeRule(orientation=math.pi)}
    graph = RoutingGraph([a, b, c], [edge(a, b, rules=forwards), edge(b, c, rules=backwards)])

    assert graph.route("a", "c", vehicle=T1).travel_time == pytest.approx(10.0 + 2.0)


def test_a_node_heading_is_turned_to_on_the_way_and_at_the_goal() -> None:
    a, b = node("a", 0, 0), node("b", 10, 0, rules={"T1": NodeRule(theta=math.pi / 2)})
    graph = RoutingGraph([a, b], [edge(a, b, rules={"T1": EdgeRule()})])

    assert graph.route("a", "b", vehicle=T1).travel_time == pytest.approx(5.0 + 1.0)


def test_elements_with_rules_for_other_types_are_unusable_and_open_ones_usable() -> None:
    a, b, c = node("a", 0, 0), node("b", 10, 0), node("c", 10, 10)
    short = edge(a, c, rules={"T2": EdgeRule()})  # only T2 may take the diagonal
    graph = RoutingGraph([a, b, c], [short, edge(a, b), edge(b, c)])

    assert graph.route("a", "c", vehicle=T1).nodes == ["a", "b", "c"]
    assert graph.route("a", "c", vehicle=Profile(vehicle_type="T2")).nodes == ["a", "c"]
    assert graph.route("a", "c").nodes == ["a", "c"]  # no type: type rules do not apply


def test_a_node_for_other_types_is_no_start_goal_or_way_through() -> None:
    a, b, c = node("a", 0, 0), node("b", 10, 0, rules={"T2": NodeRule()}), node("c", 20, 0)
    graph = RoutingGraph([a, b, c], [edge(a, b), edge(b, c)])

    with pytest.raises(NoRouteError, match="not usable"):
        graph.route("a", "b", vehicle=T1)
    with pytest.raises(NoRouteError):
        graph.route("a", "c", vehicle=T1)


def test_load_restrictions_follow_the_vehicles_load() -> None:
    a, b, c = node("a", 0, 0), node("b", 10, 0), node("c", 10, 10)
    loaded_only = edge(a, c, rules={"T1": EdgeRule(unloaded=False, load_sets=frozenset({"EUR"}))})
    graph = RoutingGraph([a, b, c], [loaded_only, edge(a, b), edge(b, c)])

    def path(**load) -> list[str]:
        return graph.route("a", "c", vehicle=Profile(vehicle_type="T1", **load)).nodes

    assert path(loaded=True, load_set="EUR") == ["a", "c"]
    assert path(loaded=True, load_set="GITTERBOX") == ["a", "b", "c"]
    assert path(loaded=False) == ["a", "b", "c"]


def test_a_trajectory_sets_the_length_driven() -> None:
    from traffic import Nurbs

    a, b = node("a", 0, 0), node("b", 4, 0)
    arc = Nurbs(2, (0, 0, 0, 1, 1, 1), ((0, 0, 1), (2, 2, 1), (4, 0, 1)))  # a bow above the line
    graph = RoutingGraph([a, b], [edge(a, b, rules={"T1": EdgeRule(trajectory=arc)})])

    route = graph.route("a", "b", vehicle=Profile(vehicle_type="T1", max_speed=1.0))

    assert route.length == pytest.approx(arc.length())
    assert route.length > 4.5


def grid(columns: int = 4, rows: int = 3) -> RoutingGraph:
    nodes = {
        (c, r): node(f"{c}.{r}", c * 2.0, r * 2.0) for c in range(columns) for r in range(rows)
    }
    edges = []
    for (c, r), here in nodes.items():
        for there in (nodes.get((c + 1, r)), nodes.get((c, r + 1))):
            if there is not None:
                edges += two_way(here, there)
    return RoutingGraph(nodes.values(), edges)


def test_k_alternatives_are_distinct_quickest_first_and_within_the_stretch() -> None:
    graph = grid()

    routes = graph.routes("0.0", "3.2", 3, vehicle=Profile(rotation_speed=1.0), max_stretch=2.0)

    assert len(routes) == 3
    assert len({tuple(r.edges) for r in routes}) == 3
    times = [r.travel_time for r in routes]
    assert times == sorted(times)
    assert times[0] == pytest.approx(
        graph.route("0.0", "3.2", vehicle=Profile(rotation_speed=1.0)).travel_time
    )
    assert times[-1] <= 2.0 * times[0]


def test_alternatives_stop_at_the_stretch_limit() -> None:
    a, b, c, d = node("a", 0, 0), node("b", 5, 0), node("c", 10, 0), node("d", 5, 30)
    graph = RoutingGraph([a, b, c, d], [edge(a, b), edge(b, c), edge(a, d), edge(d, c)])

    assert [r.nodes for r in graph.routes("a", "c", 3, max_stretch=1.5)] == [["a", "b", "c"]]
    assert len(graph.routes("a", "c", 3, max_stretch=None)) == 2


def test_the_table_route_equals_the_fresh_dijkstra_and_is_cached() -> None:
    graph = grid(6, 5)
    profile = Profile(rotation_speed=0.5)

    for start in ("0.0", "5.4", "2.3", "4.1"):
        fresh = graph.route(start, "3.0", vehicle=profile)
        cached = graph.route_from_table(start, "3.0", vehicle=profile)
        assert cached.travel_time == pytest.approx(fresh.travel_time)
        assert cached.nodes[0] == start
        assert cached.nodes[-1] == "3.0"

    times = graph.travel_times_to("3.0", vehicle=profile)
    assert times is not graph.travel_times_to("3.0", vehicle=profile)  # callers get copies
    assert graph.for_vehicle(profile)._tables.keys() == {"3.0"}
    assert times["0.0"] == pytest.approx(graph.route("0.0", "3.0", vehicle=profile).travel_time)


def test_a_start_heading_prices_the_first_turn() -> None:
    a, b = node("a", 0, 0), node("b", 10, 0)
    graph = RoutingGraph([a, b], [edge(a, b)])
    profile = Profile(max_speed=1.0, rotation_speed=math.pi / 2)

    facing = graph.route_from_table("a", "b", vehicle=profile, start_heading=0.0)
    away = graph.route_from_table("a", "b", vehicle=profile, start_heading=math.pi)

    assert facing.travel_time == pytest.approx(10.0)
    assert away.travel_time == pytest.approx(12.0)


def test_routes_cross_floors_through_transition_edges() -> None:
    ground = [node("g1", 0, 0, "floor-0"), node("lift-0", 10, 0, "floor-0")]
    upper = [node("lift-1", 10, 0, "floor-1"), node("u1", 10, 10, "floor-1")]
    edges = [
        *two_way(ground[0], ground[1]),
        *two_way(ground[1], upper[0]),  # the lift: a transition between maps
        *two_way(upper[0], upper[1]),
    ]
    graph = RoutingGraph(ground + upper, edges)

    route = graph.route("g1", "u1")

    assert route.nodes == ["g1", "lift-0", "lift-1", "u1"]
    assert route.map_ids == ["floor-0", "floor-1"]


def test_start_equals_goal_is_a_route_of_one_node() -> None:
    route = grid().route("1.1", "1.1")

    assert route.nodes == ["1.1"]
    assert route.edges == []
    assert route.travel_time == 0.0
