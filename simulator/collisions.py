"""An independent collision checker: do the footprints of simulated vehicles ever overlap?

It knows nothing of traffic management or the master control: every simulated step it takes each
vehicle's pose (x, y, theta) and its footprint rectangle from its own factsheet
(`physicalParameters.length` × `width`, centred on the kinematic centre as the simulator's
factsheet says) and tests every nearby pair with the separating-axis theorem. A collision is
counted once when a pair starts overlapping (touching is not overlapping) and logged; it is over
when they separate. Pure Python, no MQTT: the fleet calls `check` after each tick, tests may call
it directly.
"""

from __future__ import annotations

import logging
import math
from collections.abc import Iterable, Sequence
from dataclasses import dataclass, field

log = logging.getLogger(__name__)

TOLERANCE = 1e-6  # m: overlaps shallower than this count as touching
Corners = tuple[tuple[float, float], ...]


@dataclass(frozen=True, slots=True)
class Footprint:
    """A vehicle's rectangle in metres: length along its heading, width across."""

    length: float
    width: float

    @property
    def radius(self) -> float:
        """Half the diagonal: no part of the rectangle is farther from the centre."""
        return math.hypot(self.length / 2, self.width / 2)


@dataclass(frozen=True, slots=True)
class Body:
    """One vehicle at one instant."""

    name: str
    x: float
    y: float
    theta: float
    footprint: Footprint


@dataclass(frozen=True, slots=True)
class Collision:
    """Two vehicles whose footprints began to overlap at simulated time `at`."""

    first: str
    second: str
    at: float
    first_pose: tuple[float, float, float]
    second_pose: tuple[float, float, float]


def corners(body: Body) -> Corners:
    """The rectangle's corners, counter-clockwise."""
    c, s = math.cos(body.theta), math.sin(body.theta)
    hl, hw = body.footprint.length / 2, body.footprint.width / 2
    return tuple(
        (body.x + dx * c - dy * s, body.y + dx * s + dy * c)
        for dx, dy in ((hl, hw), (-hl, hw), (-hl, -hw), (hl, -hw))
    )


def _axes(points: Corners) -> Iterable[tuple[float, float]]:
    for i in range(2):  # a rectangle has two edge directions
        (x1, y1), (x2, y2) = points[i], points[i + 1]
        length = math.hypot(x2 - x1, y2 - y1) or 1.0
        yield (-(y2 - y1) / length, (x2 - x1) / length)


def overlap(a: Body, b: Body, tolerance: float = TOLERANCE) -> bool:
    """Whether two footprints overlap by more than `tolerance` (separating-axis theorem)."""
    reach = a.footprint.radius + b.footprint.radius
    if (a.x - b.x) ** 2 + (a.y - b.y) ** 2 >= reach * reach:
        return False
    pa, pb = corners(a), corners(b)
    for ax, ay in (*_axes(pa), *_axes(pb)):
        da = [x * ax + y * ay for x, y in pa]
        db = [x * ax + y * ay for x, y in pb]
        if min(max(da), max(db)) - max(min(da), min(db)) <= tolerance:
            return False
    return True


@dataclass
class CollisionChecker:
    """Counts and logs collisions across all vehicles of one simulator process."""

    tolerance: float = TOLERANCE
    steps: int = 0
    events: list[Collision] = field(default_factory=list)
    _touching: set[tuple[str, str]] = field(default_factory=set)

    @property
    def count(self) -> int:
        """Collisions so far (each pair counted once per contact)."""
        return len(self.events)

    def check(self, bodies: Sequence[Body], now: float) -> list[Collision]:
        """Test one simulated step; returns the collisions that began in it."""
        self.steps += 1
        current = set()
        new: list[Collision] = []
        for a, b in _near_pairs(bodies):
            if not overlap(a, b, self.tolerance):
                continue
            pair = (a.name, b.name) if a.name < b.name else (b.name, a.name)
            current.add(pair)
            if pair in self._touching:
                continue
            event = Collision(pair[0], pair[1], now, (a.x, a.y, a.theta), (b.x, b.y, b.theta))
            new.append(event)
            log.warning(
                "COLLISION %s at (%.2f, %.2f) and %s at (%.2f, %.2f), t=%.1f s",
                a.name,
                a.x,
                a.y,
                b.name,
                b.x,
                b.y,
                now,
            )
        self._touching = current
        self.events += new
        return new

    def summary(self) -> dict[str, object]:
        """What the simulator reports at the end (and tests read)."""
        return {
            "steps": self.steps,
            "collisions": self.count,
            "events": [
                {"vehicles": [e.first, e.second], "at": round(e.at, 2)} for e in self.events[:100]
            ],
        }


def _near_pairs(bodies: Sequence[Body]) -> Iterable[tuple[Body, Body]]:
    """Pairs close enough to touch: a uniform grid, so a thousand vehicles stay cheap."""
    if len(bodies) < 2:
        return
    cell = 2 * max(b.footprint.radius for b in bodies) or 1.0
    grid: dict[tuple[int, int], list[Body]] = {}
    for body in bodies:
        grid.setdefault((math.floor(body.x / cell), math.floor(body.y / cell)), []).append(body)
    for (cx, cy), members in grid.items():
        for i, a in enumerate(members):
            for b in members[i + 1 :]:
                yield a, b
        for dx, dy in ((1, -1), (1, 0), (1, 1), (0, 1)):  # each neighbour pair once
            for a in members:
                for b in grid.get((cx + dx, cy + dy), ()):
                    yield a, b
