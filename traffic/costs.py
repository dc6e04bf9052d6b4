"""Travel-time costs: who drives, what a vehicle type may do on an edge or node, and turning.

The rules follow LIF 1.0 (`vehicleTypeEdgeProperties`, `vehicleTypeNodeProperties`): an element
that lists rules for some vehicle types may be used only by those types. An element without any
rules is open to every vehicle (the demo warehouse, maps made before vehicle types existed), and a
profile without a vehicle type ignores type rules altogether.
"""

import math
from dataclasses import dataclass

from traffic.geometry import Nurbs, wrap

DEFAULT_SPEED = 1.0  # m/s, for a profile that names no speed
HEADING_TOLERANCE = 1e-3  # rad; smaller heading changes need no turn

NONE, CCW, CW, BOTH = "NONE", "CCW", "CW", "BOTH"
TURN_DIRECTIONS: dict[str, frozenset[str]] = {
    NONE: frozenset(),
    CCW: frozenset({CCW}),
    CW: frozenset({CW}),
    BOTH: frozenset({CCW, CW}),
}


@dataclass(frozen=True)
class VehicleProfile:
    """Who drives: a vehicle type (None: any vehicle, type rules ignored), its speeds and its load.

    `rotation_speed` (rad/s) prices turning on the spot; None makes turns free (but turn rules
    still apply). `loaded` None ignores load restrictions; `load_set` None accepts every edge that
    admits loaded vehicles. `height` (m, vehicle with load) is checked against edge `max_height`.
    """

    vehicle_type: str | None = None
    max_speed: float = DEFAULT_SPEED
    rotation_speed: float | None = None
    loaded: bool | None = None
    load_set: str | None = None
    height: float | None = None


@dataclass(frozen=True)
class NodeRule:
    """What one vehicle type does at a node: the heading it must take there (rad), if any."""

    theta: float | None = None


@dataclass(frozen=True)
class EdgeRule:
    """What one vehicle type may do on an edge (the routing part of a LIF vehicleTypeEdgeProperty).

    `orientation` is the vehicle's heading relative to the direction of travel (or absolute when
    `orientation_global`); None means driving forwards. `rotation_allowed` lets the vehicle turn
    while driving the edge, so it needs no turn on the spot at either end. `rotation_at_start` and
    `rotation_at_end` (NONE, CCW, CW, BOTH) restrict turning on the spot at the end nodes.
    """

    max_speed: float | None = None
    max_rotation_speed: float | None = None
    orientation: float | None = None
    orientation_global: bool = False
    rotation_allowed: bool = False
    rotation_at_start: str = BOTH
    rotation_at_end: str = BOTH
    unloaded: bool = True
    loaded: bool = True
    load_sets: frozenset[str] = frozenset()
    max_height: float | None = None
    trajectory: Nurbs | None = None

    def admits(self, profile: VehicleProfile) -> bool:
        """Whether a vehicle of `profile` (already of this rule's type) may drive the edge."""
        if profile.loaded is True:
            if not self.loaded:
                return False
            if self.load_sets and profile.load_set and profile.load_set not in self.load_sets:
                return False
        elif profile.loaded is False and not self.unloaded:
            return False
        return not (
            profile.height is not None
            and self.max_height is not None
            and profile.height > self.max_height
        )

    def vehicle_heading(self, travel: float | None) -> float | None:
        """The vehicle's heading while the direction of travel is `travel` (None: undefined)."""
        if self.orientation_global and self.orientation is not None:
            return wrap(self.orientation)
        if travel is None:
            return None
        return wrap(travel + (self.orientation or 0.0))


def turn_directions(*rules: str) -> frozenset[str]:
    """Directions allowed by every one of `rules` (LIF: the rules at a node combine with AND)."""
    allowed = TURN_DIRECTIONS[BOTH]
    for rule in rules:
        allowed &= TURN_DIRECTIONS.get(rule, TURN_DIRECTIONS[BOTH])
    return allowed


def turn_angle(start: float | None, end: float | None, directions: frozenset[str]) -> float | None:
    """Angle (rad, >= 0) to turn from heading `start` to `end` using only `directions`.

    An undefined heading (None) needs no turn. Returns None when the turn is needed but forbidden.
    """
    if start is None or end is None:
        return 0.0
    delta = wrap(end - start)
    if abs(delta) <= HEADING_TOLERANCE:
        return 0.0
    options = []
    if CCW in directions:
        options.append(delta % math.tau)
    if CW in directions:
        options.append(-delta % math.tau)
    return min(options) if options else None


def turn_via(
    start: float | None, middle: float | None, end: float | None, directions: frozenset[str]
) -> float | None:
    """Angle to turn from `start` to `end`, passing heading `middle` if it is given."""
    if middle is None:
        return turn_angle(start, end, directions)
    first, second = turn_angle(start, middle, directions), turn_angle(middle, end, directions)
    if first is None or second is None:
        return None
    return first + second
