"""Polygon geometry for zones: containment, how much of an edge lies inside, simple shapes."""

import math

import pytest

from maps.geometry import Polygon, angle_between, self_intersections, signed_area

SQUARE = Polygon.of([(0, 0), (0, 2), (2, 2), (2, 0)])  # given clockwise


def test_polygons_are_stored_counter_clockwise_without_repeated_points() -> None:
    polygon = Polygon.of([(0, 0), (0, 2), (0, 2), (2, 2), (2, 0), (0, 0)])

    assert signed_area(polygon.vertices) > 0
    assert len(polygon.vertices) == 4
    assert polygon.area == pytest.approx(4.0)


@pytest.mark.parametrize(
    ("point", "inside"),
    [((1, 1), True), ((2, 1), True), ((0, 0), True), ((2.01, 1), False), ((-1, -1), False)],
)
def test_points_on_the_boundary_count_as_inside(point, inside) -> None:
    assert SQUARE.contains(point) is inside


@pytest.mark.parametrize(
    ("a", "b", "metres"),
    [
        ((-1, 1), (3, 1), 2.0),  # straight through
        ((1, 1), (5, 1), 1.0),  # from inside out
        ((-1, 2), (3, 2), 2.0),  # along the boundary
        ((-1, 3), (3, 3), 0.0),  # past it
        ((-1, 1), (0, 1), 0.0),  # up to the boundary only
        ((-1, -1), (3, 3), 2 * math.sqrt(2)),  # diagonally, through two corners
    ],
)
def test_length_inside_measures_the_part_of_a_segment_in_the_polygon(a, b, metres) -> None:
    assert SQUARE.length_inside(a, b) == pytest.approx(metres)


def test_length_inside_a_concave_polygon_skips_the_notch() -> None:
    u_shape = Polygon.of([(0, 0), (3, 0), (3, 3), (2, 3), (2, 1), (1, 1), (1, 3), (0, 3)])

    assert u_shape.length_inside((-1, 2), (4, 2)) == pytest.approx(2.0)
    assert not u_shape.contains((1.5, 2))


def test_self_intersections_find_a_bow_tie_and_a_fold() -> None:
    assert self_intersections([(0, 0), (2, 2), (2, 0), (0, 2)]) == [(0, 2)]
    assert self_intersections([(0, 0), (2, 0), (1, 0), (1, 1)]) != []
    assert self_intersections(list(SQUARE.vertices)) == []


def test_overlap_needs_shared_area_not_a_shared_side() -> None:
    assert SQUARE.overlaps(Polygon.of([(1, 1), (3, 1), (3, 3), (1, 3)]))
    assert SQUARE.overlaps(Polygon.of([(0.5, 0.5), (1, 0.5), (1, 1)]))  # inside
    assert SQUARE.overlaps(SQUARE)
    assert not SQUARE.overlaps(Polygon.of([(2, 0), (4, 0), (4, 2), (2, 2)]))  # side by side
    assert not SQUARE.overlaps(Polygon.of([(5, 5), (6, 5), (6, 6)]))


def test_angle_between_wraps_around() -> None:
    assert angle_between(0.1, 2 * math.pi - 0.1) == pytest.approx(0.2)
    assert angle_between(0.0, math.pi) == pytest.approx(math.pi)


def test_fewer_than_three_points_are_no_polygon() -> None:
    with pytest.raises(ValueError, match="three"):
        Polygon.of([(0, 0), (1, 1), (1, 1)])
