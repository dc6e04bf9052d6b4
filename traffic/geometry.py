"""Geometry for routing: headings and NURBS trajectories (LIF `trajectory`, VDA 5050 `trajectory`).

A trajectory is a NURBS curve given by its degree, knot vector and weighted control points. Routing
needs two things from it: its length (the distance a vehicle drives) and its direction at both ends
(the heading a vehicle has when it enters and leaves the edge).
"""

import math
from dataclasses import dataclass

SAMPLES_PER_SPAN = 16  # sample points per knot span when measuring a curve's length


def heading(dx: float, dy: float) -> float | None:
    """Direction of the vector (dx, dy) in rad, or None for a vector of (almost) zero length."""
    if math.hypot(dx, dy) < 1e-9:
        return None
    return math.atan2(dy, dx)


def wrap(angle: float) -> float:
    """`angle` mapped to (-pi, pi]."""
    wrapped = math.remainder(angle, math.tau)
    return math.pi if wrapped == -math.pi else wrapped


@dataclass(frozen=True)
class Nurbs:
    """A NURBS curve: `points` are (x, y, weight) control points, `knots` the knot vector."""

    degree: int
    knots: tuple[float, ...]
    points: tuple[tuple[float, float, float], ...]

    def __post_init__(self) -> None:
        if self.degree < 1:
            raise ValueError("degree must be at least 1")
        if len(self.points) < self.degree + 1:
            raise ValueError("a NURBS needs at least degree + 1 control points")
        if len(self.knots) != len(self.points) + self.degree + 1:
            raise ValueError("the knot vector needs (control points + degree + 1) entries")
        if any(b < a for a, b in zip(self.knots, self.knots[1:], strict=False)):
            raise ValueError("knots must not decrease")
        if any(w <= 0 for _, _, w in self.points):
            raise ValueError("weights must be positive")

    def point(self, u: float) -> tuple[float, float]:
        """The curve point at parameter `u` (clamped to the knot range)."""
        p, knots = self.degree, self.knots
        low, high = knots[p], knots[len(self.points)]
        u = min(max(u, low), high)
        span = self._span(u)
        basis = self._basis(span, u)
        x = y = w = 0.0
        for j, n in enumerate(basis):
            px, py, pw = self.points[span - p + j]
            x, y, w = x + n * pw * px, y + n * pw * py, w + n * pw
        return x / w, y / w

    def length(self) -> float:
        """Arc length, measured along a polyline of sample points (good to well under 1 %)."""
        p, knots = self.degree, self.knots
        params: list[float] = []
        last = len(self.points)
        for a, b in zip(knots[p:last], knots[p + 1 : last + 1], strict=True):
            if b > a:
                params.extend(a + (b - a) * i / SAMPLES_PER_SPAN for i in range(SAMPLES_PER_SPAN))
        params.append(knots[len(self.points)])
        samples = [self.point(u) for u in params]
        return sum(math.dist(a, b) for a, b in zip(samples, samples[1:], strict=False))

    def start_heading(self) -> float | None:
        """Direction of travel where the curve starts (clamped curves leave along P0 → P1)."""
        first = self.points[0]
        for x, y, _ in self.points[1:]:
            direction = heading(x - first[0], y - first[1])
            if direction is not None:
                return direction
        return None

    def end_heading(self) -> float | None:
        """Direction of travel where the curve ends (clamped curves arrive along Pn-1 → Pn)."""
        last = self.points[-1]
        for x, y, _ in reversed(self.points[:-1]):
            direction = heading(last[0] - x, last[1] - y)
            if direction is not None:
                return direction
        return None

    def _span(self, u: float) -> int:
        n, p, knots = len(self.points) - 1, self.degree, self.knots
        if u >= knots[n + 1]:
            return n
        span = p
        while span < n and u >= knots[span + 1]:
            span += 1
        return span

    def _basis(self, span: int, u: float) -> list[float]:
        """The p + 1 non-zero B-spline basis functions at `u` (The NURBS Book, A2.2)."""
        p, knots = self.degree, self.knots
        basis, left, right = [1.0] + [0.0] * p, [0.0] * (p + 1), [0.0] * (p + 1)
        for j in range(1, p + 1):
            left[j], right[j] = u - knots[span + 1 - j], knots[span + j] - u
            saved = 0.0
            for r in range(j):
                denominator = right[r + 1] + left[j - r]
                temp = basis[r] / denominator if denominator else 0.0
                basis[r] = saved + right[r + 1] * temp
                saved = left[j - r] * temp
            basis[j] = saved
        return basis
