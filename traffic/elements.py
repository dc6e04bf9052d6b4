"""The plain data routing works on: nodes, directed edges and the routes found between them."""

from collections.abc import Mapping
from dataclasses import dataclass, field

from traffic.costs import EdgeRule, NodeRule, VehicleProfile


class NoRouteError(Exception):
    """No directed path exists between two nodes (or a node is not in the layout)."""


@dataclass(frozen=True)
class GraphNode:
    """A node of the layout: position (m), the map (floor) it is on, heading to hold (rad).

    `rules` maps vehicle type ids to what each type does here; a node with rules is usable only
    by those types, one without rules by every vehicle.
    """

    node_id: str
    x: float = 0.0
    y: float = 0.0
    map_id: str = ""
    theta: float | None = None
    rules: Mapping[str, NodeRule] = field(default_factory=dict, compare=False, hash=False)

    def usable_by(self, profile: VehicleProfile) -> bool:
        """Whether a vehicle of `profile` may use this node."""
        return not self.rules or profile.vehicle_type is None or profile.vehicle_type in self.rules

    def theta_for(self, profile: VehicleProfile) -> float | None:
        """The heading a vehicle of `profile` must have on this node, if any."""
        rule = self.rules.get(profile.vehicle_type or "") if self.rules else None
        return rule.theta if rule is not None and rule.theta is not None else self.theta


@dataclass(frozen=True)
class GraphEdge:
    """A directed, traversable edge of the layout with its length in metres.

    `max_speed` (m/s) limits every vehicle; `rules` maps vehicle type ids to what each type may do
    on the edge (an edge with rules is usable only by those types). `cost_factor` scales what
    routing pays for the edge in both views, travel time and distance (zones: above 1 in a
    penalty zone, below 1 in a priority zone); lengths stay true, route times become costs.
    """

    edge_id: str
    start: str
    end: str
    length: float
    max_speed: float | None = None
    rules: Mapping[str, EdgeRule] = field(default_factory=dict, compare=False, hash=False)
    cost_factor: float = 1.0

    def rule_for(self, profile: VehicleProfile) -> EdgeRule | None:
        """The rule a vehicle of `profile` drives by: an open default, or None if it may not."""
        if not self.rules or profile.vehicle_type is None:
            return OPEN
        rule = self.rules.get(profile.vehicle_type)
        return rule if rule is not None and rule.admits(profile) else None


OPEN = EdgeRule()


@dataclass(frozen=True)
class Route:
    """A route: node ids (start to goal inclusive), the edge ids driven, seconds and metres."""

    nodes: list[str]
    edges: list[str]
    travel_time: float
    length: float
    map_ids: list[str] = field(default_factory=list)
