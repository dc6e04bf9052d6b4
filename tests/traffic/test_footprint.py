"""Footprint conflict sets computed from vehicle geometry."""

import math

from traffic.footprint import ConflictSets, VehicleClass
from traffic.layout import Layout

AMR = VehicleClass(length=0.8, width=0.5)


def lanes(gap: float) -> Layout:
    """Two parallel two-way lanes, `gap` metres apart, 4 m long."""
    nodes = [("a0", 0.0, 0.0), ("a1", 4.0, 0.0), ("b0", 0.0, gap), ("b1", 4.0, gap)]
    edges = [("a0", "a1", None, None), ("a1", "a0", None, None)]
    edges += [("b0", "b1", None, None), ("b1", "b0", None, None)]
    return Layout(nodes, edges)


def segment(layout: Layout, start: str, end: str) -> int:
    edge = next(
        e
        for e, x in enumerate(layout.edges)
        if (x.start, x.end) == (layout.node(start), layout.node(end))
    )
    return layout.segment_resource(edge)


def test_both_directions_of_a_lane_share_one_segment() -> None:
    layout = lanes(3.0)
    assert segment(layout, "a0", "a1") == segment(layout, "a1", "a0")
    assert layout.resource_count == 4 + 2


def test_near_parallel_lanes_closer_than_the_vehicle_width_conflict() -> None:
    close = lanes(0.4)  # 0.4 m apart, vehicles 0.5 m wide
    sets = ConflictSets(close, [AMR])
    assert sets.conflict(0, segment(close, "a0", "a1"), segment(close, "b0", "b1"))
    far = lanes(1.0)
    sets = ConflictSets(far, [AMR])
    assert not sets.conflict(0, segment(far, "a0", "a1"), segment(far, "b0", "b1"))


def test_a_slightly_skewed_lane_conflicts_where_it_comes_close() -> None:
    nodes = [("a0", 0.0, 0.0), ("a1", 6.0, 0.0), ("b0", 0.0, 2.0), ("b1", 6.0, 0.45)]
    layout = Layout(nodes, [("a0", "a1", None, None), ("b0", "b1", None, None)])
    sets = ConflictSets(layout, [AMR])
    assert sets.conflict(0, segment(layout, "a0", "a1"), segment(layout, "b0", "b1"))
    assert not sets.conflict(0, layout.node("a0"), layout.node("b0"))


def test_grid_conflicts_follow_the_swept_footprints() -> None:
    layout = Layout.grid([(0, c) for c in range(4)] + [(1, 1)])
    sets = ConflictSets(layout, [AMR])
    n = layout.node
    s01, s12, s23 = (
        segment(layout, "0,0", "0,1"),
        segment(layout, "0,1", "0,2"),
        segment(layout, "0,2", "0,3"),
    )
    side = segment(layout, "0,1", "1,1")
    assert sets.conflict(0, n("0,1"), n("0,1"))  # itself
    assert not sets.conflict(0, n("0,1"), n("0,2"))  # neighbours 1 m apart: discs of 0.47 m
    assert sets.conflict(0, s01, n("0,1"))
    assert sets.conflict(0, s01, n("0,0"))
    assert sets.conflict(0, s01, s12)
    assert sets.conflict(0, s01, side)
    assert not sets.conflict(0, s01, s23)
    assert not sets.conflict(0, s01, n("0,2"))


def test_a_vehicle_that_does_not_turn_on_the_spot_has_a_smaller_node_footprint() -> None:
    layout = Layout.grid([(0, c) for c in range(3)], pitch=0.9)
    turning = ConflictSets(layout, [VehicleClass(length=0.8, width=0.8)])
    straight = ConflictSets(layout, [VehicleClass(length=0.8, width=0.8, turns_on_spot=False)])
    assert turning.conflict(0, layout.node("0,0"), layout.node("0,1"))  # radius 0.57 > 0.45
    assert not straight.conflict(0, layout.node("0,0"), layout.node("0,1"))
    assert math.isclose(VehicleClass(length=0.6, width=0.8).radius, 0.5)


def test_mixed_classes_are_conservative() -> None:
    layout = Layout.grid([(0, c) for c in range(3)])
    big = VehicleClass("big", length=1.4, width=1.0)
    sets = ConflictSets(layout, [AMR, big])
    small, large = 0, 1
    assert sets.conflict(large, layout.node("0,0"), layout.node("0,1"))
    assert sets.conflict(small, layout.node("0,0"), layout.node("0,1"))  # against the big one
