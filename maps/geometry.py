"""Plane geometry for zones, framework-free: simple polygons, points and segments in metres.

Small enough to do by hand (no shapely): a zone has a handful of vertices, and routing asks only
whether a node lies in a zone and how much of an edge's straight line runs through it. Points on
a polygon's boundary count as inside, so a zone drawn along an aisle catches that aisle.
"""

import math
from collections.abc import Iterable, Sequence
from dataclasses import dataclass

Point = tuple[float, float]
EPSILON = 1e-9  # m: closer than this is "on" a line


def signed_area(vertices: Sequence[Point]) -> float:
    """Shoelace area: positive for counter-clockwise vertices, negative for clockwise."""
    total = 0.0
    for (x1, y1), (x2, y2) in zip(vertices, [*vertices[1:], vertices[0]], strict=True):
        total += x1 * y2 - x2 * y1
    return total / 2.0


def segments_cross(a: Point, b: Point, c: Point, d: Point) -> bool:
    """Whether segments a-b and c-d share a point (touching and overlapping count)."""
    d1, d2 = _orientation(c, d, a), _orientation(c, d, b)
    d3, d4 = _orientation(a, b, c), _orientation(a, b, d)
    if ((d1 > 0 and d2 < 0) or (d1 < 0 and d2 > 0)) and (
        (d3 > 0 and d4 < 0) or (d3 < 0 and d4 > 0)
    ):
        return True
    return (
        (d1 == 0 and _on_segment(c, d, a))
        or (d2 == 0 and _on_segment(c, d, b))
        or (d3 == 0 and _on_segment(a, b, c))
        or (d4 == 0 and _on_segment(a, b, d))
    )


def self_intersections(vertices: Sequence[Point]) -> list[tuple[int, int]]:
    """Pairs of polygon sides (by index of their first vertex) that cross; [] for a simple one.

    Side i runs from vertex i to vertex i + 1 (the last one back to vertex 0). Neighbouring sides
    share a vertex and are only reported when they fold back onto each other.
    """
    n = len(vertices)
    sides = [(vertices[i], vertices[(i + 1) % n]) for i in range(n)]
    found = []
    for i in range(n):
        for j in range(i + 1, n):
            a, b = sides[i]
            c, d = sides[j]
            if j == i + 1 or (i == 0 and j == n - 1):
                shared = b if j == i + 1 else a
                other_i, other_j = (a, d) if j == i + 1 else (b, c)
                if _folds_back(shared, other_i, other_j):
                    found.append((i, j))
            elif segments_cross(a, b, c, d):
                found.append((i, j))
    return found


@dataclass(frozen=True)
class Polygon:
    """A simple polygon (at least three vertices), stored counter-clockwise."""

    vertices: tuple[Point, ...]
    min_x: float
    min_y: float
    max_x: float
    max_y: float

    @classmethod
    def of(cls, points: Iterable[Sequence[float]]) -> "Polygon":
        """The polygon through `points`, turned counter-clockwise if they run clockwise."""
        vertices = _distinct(tuple((float(p[0]), float(p[1])) for p in points))
        if len(vertices) < 3:
            raise ValueError("a polygon needs at least three vertices")
        if signed_area(vertices) < 0:
            vertices = vertices[::-1]
        xs, ys = [v[0] for v in vertices], [v[1] for v in vertices]
        return cls(vertices, min(xs), min(ys), max(xs), max(ys))

    @property
    def area(self) -> float:
        return abs(signed_area(self.vertices))

    def contains(self, point: Point) -> bool:
        """Whether `point` is inside the polygon or on its boundary."""
        x, y = point
        if not self._near_box(x, y, x, y):
            return False
        inside = False
        for a, b in self._sides():
            if _orientation(a, b, point) == 0 and _on_segment(a, b, point):
                return True
            (x1, y1), (x2, y2) = a, b
            if (y1 > y) != (y2 > y) and x < x1 + (y - y1) * (x2 - x1) / (y2 - y1):
                inside = not inside
        return inside

    def length_inside(self, a: Point, b: Point) -> float:
        """How many metres of the segment a-b lie inside the polygon (boundary included)."""
        if not self._near_box(min(a[0], b[0]), min(a[1], b[1]), max(a[0], b[0]), max(a[1], b[1])):
            return 0.0
        length = math.dist(a, b)
        if length < EPSILON:
            return 0.0
        cuts = sorted({0.0, 1.0, *self._crossings(a, b)})
        inside = 0.0
        for t0, t1 in zip(cuts, cuts[1:], strict=False):
            middle = (t0 + t1) / 2
            if self.contains((a[0] + (b[0] - a[0]) * middle, a[1] + (b[1] - a[1]) * middle)):
                inside += (t1 - t0) * length
        return inside

    def touches_segment(self, a: Point, b: Point) -> bool:
        """Whether the segment a-b has any point inside the polygon or on its boundary."""
        if not self._near_box(min(a[0], b[0]), min(a[1], b[1]), max(a[0], b[0]), max(a[1], b[1])):
            return False
        if self.contains(a) or self.contains(b):
            return True
        return any(segments_cross(a, b, c, d) for c, d in self._sides())

    def overlaps(self, other: "Polygon") -> bool:
        """Whether the two polygons share interior area (touching along a side does not count)."""
        if not self._near_box(other.min_x, other.min_y, other.max_x, other.max_y):
            return False
        if self._runs_through(other) or other._runs_through(self):
            return True
        # No side runs through the other's interior: apart, touching, or the very same shape.
        a, b = self.vertices[0], self.vertices[1]
        length = math.dist(a, b)
        inward = (-(b[1] - a[1]) / length, (b[0] - a[0]) / length)  # left of a side, as CCW
        probe = ((a[0] + b[0]) / 2 + inward[0] * 1e-6, (a[1] + b[1]) / 2 + inward[1] * 1e-6)
        return other.contains(probe) and not other._on_boundary(probe)

    def _runs_through(self, other: "Polygon") -> bool:
        """Whether a side of self passes through the interior of `other`."""
        for a, b in self._sides():
            cuts = sorted({0.0, 1.0, *other._crossings(a, b)})
            for t0, t1 in zip(cuts, cuts[1:], strict=False):
                middle = (t0 + t1) / 2
                point = (a[0] + (b[0] - a[0]) * middle, a[1] + (b[1] - a[1]) * middle)
                if other.contains(point) and not other._on_boundary(point):
                    return True
        return False

    def _on_boundary(self, point: Point) -> bool:
        return any(
            _orientation(a, b, point) == 0 and _on_segment(a, b, point) for a, b in self._sides()
        )

    def _sides(self) -> Iterable[tuple[Point, Point]]:
        vertices = self.vertices
        return zip(vertices, [*vertices[1:], vertices[0]], strict=True)

    def _near_box(self, min_x: float, min_y: float, max_x: float, max_y: float) -> bool:
        return not (
            max_x < self.min_x - EPSILON
            or min_x > self.max_x + EPSILON
            or max_y < self.min_y - EPSILON
            or min_y > self.max_y + EPSILON
        )

    def _crossings(self, a: Point, b: Point) -> list[float]:
        """Parameters t in (0, 1) where a + t (b - a) meets a side of the polygon."""
        found = []
        rx, ry = b[0] - a[0], b[1] - a[1]
        for c, d in self._sides():
            sx, sy = d[0] - c[0], d[1] - c[1]
            denominator = rx * sy - ry * sx
            qx, qy = c[0] - a[0], c[1] - a[1]
            if abs(denominator) < EPSILON:
                # parallel: collinear sides add their end points as cuts
                if abs(qx * ry - qy * rx) < EPSILON:
                    squared = rx * rx + ry * ry
                    for px, py in (c, d):
                        t = ((px - a[0]) * rx + (py - a[1]) * ry) / squared
                        if 0.0 < t < 1.0:
                            found.append(t)
                continue
            t = (qx * sy - qy * sx) / denominator
            u = (qx * ry - qy * rx) / denominator
            if 0.0 < t < 1.0 and -EPSILON <= u <= 1.0 + EPSILON:
                found.append(t)
        return found


def angle_between(a: float, b: float) -> float:
    """The absolute difference of two directions (rad), in [0, pi]."""
    return abs(math.remainder(a - b, math.tau))


def _orientation(a: Point, b: Point, c: Point) -> int:
    """+1 if a-b-c turns left, -1 if right, 0 if (nearly) collinear."""
    value = (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])
    scale = max(1.0, math.dist(a, b))
    if abs(value) < EPSILON * scale:
        return 0
    return 1 if value > 0 else -1


def _on_segment(a: Point, b: Point, c: Point) -> bool:
    """Whether c, known to be collinear with a-b, lies between a and b."""
    return (
        min(a[0], b[0]) - EPSILON <= c[0] <= max(a[0], b[0]) + EPSILON
        and min(a[1], b[1]) - EPSILON <= c[1] <= max(a[1], b[1]) + EPSILON
    )


def _folds_back(shared: Point, p: Point, q: Point) -> bool:
    """Whether two sides meeting at `shared` and ending at p and q overlap along a line."""
    if _orientation(shared, p, q) != 0:
        return False
    return (p[0] - shared[0]) * (q[0] - shared[0]) + (p[1] - shared[1]) * (q[1] - shared[1]) > 0


def _distinct(vertices: tuple[Point, ...]) -> tuple[Point, ...]:
    """`vertices` without repeats of the previous one (and without a closing copy of the first)."""
    kept: list[Point] = []
    for vertex in vertices:
        if not kept or math.dist(kept[-1], vertex) > EPSILON:
            kept.append(vertex)
    if len(kept) > 1 and math.dist(kept[0], kept[-1]) <= EPSILON:
        kept.pop()
    return tuple(kept)
