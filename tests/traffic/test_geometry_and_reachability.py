"""NURBS geometry for trajectories, and the reachability analysis behind validation."""

import math

import pytest

from traffic import EdgeRule, GraphEdge, GraphNode, Nurbs, RoutingGraph, VehicleProfile
from traffic.costs import turn_angle, turn_directions
from traffic.reachability import analyse


def test_a_degree_one_nurbs_is_its_polyline() -> None:
    line = Nurbs(1, (0, 0, 0.5, 1, 1), ((0, 0, 1), (3, 0, 1), (3, 4, 1)))

    assert line.point(0.0) == pytest.approx((0, 0))
    assert line.point(1.0) == pytest.approx((3, 4))
    assert line.length() == pytest.approx(7.0)
    assert line.start_heading() == pytest.approx(0.0)
    assert line.end_heading() == pytest.approx(math.pi / 2)


def test_a_rational_quadratic_draws_a_quarter_circle() -> None:
    w = math.sqrt(0.5)
    arc = Nurbs(2, (0, 0, 0, 1, 1, 1), ((1, 0, 1), (1, 1, w), (0, 1, 1)))

    for u in (0.1, 0.5, 0.9):
        assert math.hypot(*arc.point(u)) == pytest.approx(1.0)
    assert arc.length() == pytest.approx(math.pi / 2, rel=1e-3)


@pytest.mark.parametrize(
    ("degree", "knots", "points"),
    [
        (2, (0, 0, 1, 1), ((0, 0, 1), (1, 1, 1), (2, 0, 1))),  # too few knots
        (1, (0, 0.5, 0.2, 1), ((0, 0, 1), (1, 1, 1))),  # decreasing knots
        (1, (0, 0, 1, 1), ((0, 0, 1), (1, 1, 0))),  # zero weight
    ],
)
def test_inconsistent_nurbs_are_refused(degree, knots, points) -> None:
    with pytest.raises(ValueError, match="knot|weight"):
        Nurbs(degree, knots, points)


def test_turn_rules_combine_with_and() -> None:
    assert turn_directions("CCW", "BOTH") == {"CCW"}
    assert turn_directions("CCW", "CW") == frozenset()
    assert turn_angle(0.0, math.pi / 2, frozenset({"CW"})) == pytest.approx(3 * math.pi / 2)
    assert turn_angle(0.0, 0.0005, frozenset()) == 0.0  # within tolerance: no turn needed
    assert turn_angle(0.0, 1.0, frozenset()) is None


def test_reachability_finds_the_main_area_unreachable_nodes_and_dead_ends() -> None:
    nodes = [GraphNode(n) for n in ("a", "b", "c", "island", "source", "sink")]
    edges = [
        GraphEdge("ab", "a", "b", 1),
        GraphEdge("ba", "b", "a", 1),
        GraphEdge("bc", "b", "c", 1),
        GraphEdge("cb", "c", "b", 1),
        GraphEdge("source-a", "source", "a", 1),
        GraphEdge("c-sink", "c", "sink", 1),
    ]

    reach = analyse(RoutingGraph(nodes, edges))

    assert reach.main == {"a", "b", "c"}
    assert reach.unreachable == {"island", "source"}
    assert reach.dead_ends == {"sink"}
    assert reach.way_back("a", "c")
    assert not reach.way_back("c", "sink")


def test_reachability_respects_vehicle_type_rules() -> None:
    nodes = [GraphNode("a"), GraphNode("b")]
    edges = [GraphEdge("ab", "a", "b", 1), GraphEdge("ba", "b", "a", 1, rules={"T2": EdgeRule()})]
    graph = RoutingGraph(nodes, edges)

    assert analyse(graph).main == {"a", "b"}
    assert analyse(graph, VehicleProfile(vehicle_type="T1")).dead_ends == {"b"}
