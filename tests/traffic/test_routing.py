import pytest

from traffic import NoRouteError, RoutingGraph
from traffic.routing import GraphEdge


def line_graph() -> RoutingGraph:
    edges = [
        GraphEdge("ab", "a", "b", 1.0),
        GraphEdge("bc", "b", "c", 2.0),
        GraphEdge("ac", "a", "c", 5.0),
        GraphEdge("cb", "c", "b", 2.0),
    ]
    return RoutingGraph(["a", "b", "c", "d"], edges)


def test_shortest_path_prefers_the_shorter_detour() -> None:
    assert line_graph().shortest_path("a", "c") == ["a", "b", "c"]


def test_path_to_itself_is_the_node() -> None:
    assert line_graph().shortest_path("b", "b") == ["b"]


def test_edges_are_directed() -> None:
    with pytest.raises(NoRouteError):
        line_graph().shortest_path("c", "a")


def test_unknown_and_isolated_nodes_have_no_route() -> None:
    graph = line_graph()
    with pytest.raises(NoRouteError):
        graph.shortest_path("a", "d")
    with pytest.raises(NoRouteError):
        graph.shortest_path("a", "zzz")


def test_distances_to_goal_follow_edge_direction() -> None:
    assert line_graph().distances_to("c") == {"a": 3.0, "b": 2.0, "c": 0.0}


def test_parallel_edges_keep_the_shortest() -> None:
    graph = RoutingGraph(
        ["a", "b"], [GraphEdge("long", "a", "b", 9.0), GraphEdge("short", "a", "b", 1.0)]
    )
    assert graph.edge_between("a", "b").edge_id == "short"
    assert graph.path_length(["a", "b"]) == 1.0
