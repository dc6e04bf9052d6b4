"""Footprint conflict sets: which resources a vehicle class may not share with another vehicle.

A vehicle class is a rectangle (length along the direction of travel, width across) plus a safety
margin (load overhang, `allowedDeviationXY`). Its footprint

- on a node is the disc the rectangle sweeps when it turns on the spot there (or, for a class
  that never turns on the spot, the union of the rectangles along the edges at that node);
- on a segment is the rectangle swept along the straight segment, ends included.

Two resources conflict when their footprints overlap (touching is not overlapping). Every
resource conflicts with itself. Computed once per layout with shapely's STRtree.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import shapely
from shapely.geometry import Point, Polygon
from shapely.ops import unary_union

from traffic.layout import Layout

OVERLAP = 1e-9  # m²: intersections smaller than this are touching, not overlapping


@dataclass(frozen=True)
class VehicleClass:
    """A vehicle type as traffic sees it: size (m), speeds, and how it turns."""

    name: str = "default"
    length: float = 0.8
    width: float = 0.5
    margin: float = 0.0
    speed: float = 1.0  # m/s
    rotation_speed: float | None = None  # rad/s for turning on the spot; None: turning is free
    turns_on_spot: bool = True

    @property
    def radius(self) -> float:
        """Half the diagonal plus the margin: what turning on the spot sweeps."""
        return math.hypot(self.length / 2, self.width / 2) + self.margin


def segment_polygon(
    a: tuple[float, float], b: tuple[float, float], vehicle: VehicleClass
) -> Polygon:
    """The area `vehicle` sweeps driving straight from `a` to `b` (heading along the segment)."""
    (xa, ya), (xb, yb) = a, b
    length = math.hypot(xb - xa, yb - ya)
    ux, uy = (xb - xa) / length, (yb - ya) / length
    half_l, half_w = vehicle.length / 2 + vehicle.margin, vehicle.width / 2 + vehicle.margin
    nx, ny = -uy * half_w, ux * half_w
    back = (xa - ux * half_l, ya - uy * half_l)
    front = (xb + ux * half_l, yb + uy * half_l)
    return Polygon(
        [
            (back[0] + nx, back[1] + ny),
            (front[0] + nx, front[1] + ny),
            (front[0] - nx, front[1] - ny),
            (back[0] - nx, back[1] - ny),
        ]
    )


def footprints(layout: Layout, vehicle: VehicleClass) -> list[Polygon]:
    """The footprint of every resource (nodes first, then segments) for `vehicle`."""
    shapes: list[Polygon] = []
    for node, (x, y) in enumerate(layout.xy):
        if vehicle.turns_on_spot:
            shapes.append(Point(x, y).buffer(vehicle.radius, quad_segs=16))
            continue
        rectangles = []
        for e in layout.out[node]:
            edge = layout.edges[e]
            dx, dy = math.cos(edge.heading) * 1e-3, math.sin(edge.heading) * 1e-3
            rectangles.append(segment_polygon((x - dx, y - dy), (x + dx, y + dy), vehicle))
        union = unary_union(rectangles) if rectangles else Point(x, y).buffer(vehicle.radius)
        shapes.append(union)
    for a, b in layout.segment_ends:
        shapes.append(segment_polygon(layout.xy[a], layout.xy[b], vehicle))
    return shapes


class ConflictSets:
    """Per vehicle class, per resource: the resources it conflicts with (itself included).

    With several classes the sets are conservative: class c's resource r conflicts with r' if
    c's footprint on r overlaps *any* class's footprint on r'. With one class they are exact.
    """

    def __init__(self, layout: Layout, classes: Sequence[VehicleClass]) -> None:
        if not classes:
            raise ValueError("at least one vehicle class is needed")
        self.classes = tuple(classes)
        shapes = [np.asarray(footprints(layout, c), dtype=object) for c in self.classes]
        trees = [shapely.STRtree(s) for s in shapes]
        count = layout.resource_count
        self.sets: list[list[tuple[int, ...]]] = []
        for mine in shapes:
            found: list[set[int]] = [{r} for r in range(count)]
            for other, tree in zip(shapes, trees, strict=True):
                pairs = tree.query(mine, predicate="intersects")
                left, right = pairs[0], pairs[1]
                areas = shapely.area(shapely.intersection(mine[left], other[right]))
                for r, r2, area in zip(left.tolist(), right.tolist(), areas.tolist(), strict=True):
                    if area > OVERLAP:
                        found[r].add(r2)
            self.sets.append([tuple(sorted(s)) for s in found])

    @classmethod
    def cells(cls, layout: Layout, classes: Sequence[VehicleClass]) -> ConflictSets:
        """Grid rules (LoRR): every resource conflicts only with itself. A node is one cell
        that one vehicle may occupy, a segment is shared by both directions (no swapping);
        a vehicle may enter a cell that another one is leaving (`TrafficManager(
        grid_rules=True)` clears a node hold on leaving)."""
        sets = cls.__new__(cls)
        sets.classes = tuple(classes)
        own: list[tuple[int, ...]] = [(r,) for r in range(layout.resource_count)]
        sets.sets = [own for _ in sets.classes]
        return sets

    def of(self, vehicle_class: int, resource: int) -> tuple[int, ...]:
        """The resources that `resource` (used by class index `vehicle_class`) conflicts with."""
        return self.sets[vehicle_class][resource]

    def conflict(self, vehicle_class: int, a: int, b: int) -> bool:
        """Whether resources `a` and `b` conflict for class `vehicle_class`."""
        return b in self.sets[vehicle_class][a]
