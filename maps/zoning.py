"""Zones and what they do to routing, framework-free: plain rules in, `traffic` edges out.

A zone is a polygon on one map. Its type says what it does (VDA 5050 3.0 zone types, plus a few
of our own that LIF and VDA 5050 lack):

BLOCKED                  no vehicle enters: every edge into or within the zone is dropped. Edges
                         from a node inside to one outside are kept, so a vehicle caught inside
                         can still leave.
RESTRICTED (ours)        like BLOCKED, except for the vehicle types it lists.
SPEED_LIMIT              an edge running through the zone gets the zone's limit (whole edge, as a
                         VDA 5050 order carries one maxSpeed per edge), so travel time grows.
DIRECTED                 one-way: edges inside driving against `direction` (more than 90° off)
                         are dropped (RESTRICTED, STRICT) or cost DIRECTED_SOFT_FACTOR times more
                         (SOFT).
PENALTY, PRIORITY        the part of an edge inside costs more (1 / (1 - penaltyFactor), capped)
                         or less (1 - priorityFactor / 2) in both routing views.
BIDIRECTED, LINE_GUIDED, RELEASE, COORDINATED_REPLANNING, ACTION
                         stored, validated and exported for vehicles and the master control;
                         routing on a fixed graph has nothing to change for them.
NO_STOPPING, PARKING, CHARGING (ours)
                         areas for layout validation (stations in a no-stopping zone, parking
                         and charging stations outside their areas).

Only the straight line between an edge's nodes is tested (not a NURBS trajectory). An edge
between two maps (a lift) is only checked for entering a blocked zone at its end node.
"""

import math
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass, field, replace
from typing import Any

from maps.geometry import Polygon, angle_between, self_intersections
from traffic import EdgeRule, GraphEdge, GraphNode

BLOCKED = "BLOCKED"
RESTRICTED = "RESTRICTED"
SPEED_LIMIT = "SPEED_LIMIT"
DIRECTED = "DIRECTED"
BIDIRECTED = "BIDIRECTED"
NO_STOPPING = "NO_STOPPING"
PARKING = "PARKING"
CHARGING = "CHARGING"
LINE_GUIDED = "LINE_GUIDED"
RELEASE = "RELEASE"
COORDINATED_REPLANNING = "COORDINATED_REPLANNING"
ACTION = "ACTION"
PRIORITY = "PRIORITY"
PENALTY = "PENALTY"

VDA_TYPES = frozenset(
    {
        BLOCKED,
        LINE_GUIDED,
        RELEASE,
        COORDINATED_REPLANNING,
        SPEED_LIMIT,
        ACTION,
        PRIORITY,
        PENALTY,
        DIRECTED,
        BIDIRECTED,
    }
)
CLOSING = frozenset({BLOCKED, RESTRICTED})
SOFT, STRICT = "SOFT", "STRICT"
LIMITATIONS = {DIRECTED: ("SOFT", "RESTRICTED", "STRICT"), BIDIRECTED: ("SOFT", "RESTRICTED")}
RELEASE_LOSS = ("STOP", "CONTINUE", "EVACUATE")
# The zone fields (model names) that `zone_problems` checks, i.e. its keyword arguments.
ZONE_RULE_FIELDS = (
    "zone_type",
    "vertices",
    "max_speed",
    "direction",
    "limitation",
    "penalty_factor",
    "priority_factor",
    "release_loss_behavior",
)

MIN_INSIDE = 0.01  # m of an edge inside a zone before the zone counts for it
AGAINST = math.pi / 2 + 0.01  # rad off the one-way direction that counts as driving against it
DIRECTED_SOFT_FACTOR = 5.0  # cost of driving against a SOFT one-way zone
MAX_PENALTY_FACTOR = 1000.0  # cost multiplier of penaltyFactor 1 ("only if nothing else")
PRIORITY_GAIN = 0.5  # priorityFactor 1 halves the cost inside


@dataclass(frozen=True)
class ZoneRule:
    """An enabled zone as routing sees it. Unused fields stay None for types that lack them."""

    zone_id: str
    map_id: str
    zone_type: str
    polygon: Polygon
    max_speed: float | None = None
    direction: float | None = None
    limitation: str = ""
    penalty_factor: float | None = None
    priority_factor: float | None = None
    vehicle_types: frozenset[str] = field(default_factory=frozenset)


def penalty_multiplier(penalty_factor: float) -> float:
    """Cost multiplier inside a PENALTY zone: 1 / (1 - factor), at most MAX_PENALTY_FACTOR."""
    if penalty_factor >= 1.0:
        return MAX_PENALTY_FACTOR
    return min(MAX_PENALTY_FACTOR, 1.0 / (1.0 - max(0.0, penalty_factor)))


def priority_multiplier(priority_factor: float) -> float:
    """Cost multiplier inside a PRIORITY zone: 1 - factor × PRIORITY_GAIN."""
    return 1.0 - PRIORITY_GAIN * min(1.0, max(0.0, priority_factor))


def apply_zones(
    nodes: Mapping[str, GraphNode], edges: Iterable[GraphEdge], zones: Sequence[ZoneRule]
) -> list[GraphEdge]:
    """`edges` as the zones leave them: dropped, slowed down, or costlier (see module doc)."""
    by_map: dict[str, list[ZoneRule]] = {}
    for zone in zones:
        by_map.setdefault(zone.map_id, []).append(zone)
    if not by_map:
        return list(edges)
    result = []
    for edge in edges:
        changed = _apply(edge, nodes, by_map)
        if changed is not None:
            result.append(changed)
    return result


def closed_nodes(nodes: Iterable[GraphNode], zones: Sequence[ZoneRule]) -> dict[str, str]:
    """Node id → id of the zone that closes it, for nodes inside a zone no vehicle may enter."""
    closing = [z for z in zones if z.zone_type == BLOCKED or _closed_to_all(z)]
    found: dict[str, str] = {}
    for node in nodes:
        for zone in closing:
            if zone.map_id == node.map_id and zone.polygon.contains((node.x, node.y)):
                found[node.node_id] = zone.zone_id
                break
    return found


def zones_at(point: tuple[float, float], zones: Iterable[ZoneRule]) -> list[ZoneRule]:
    """The zones containing `point` (boundary included)."""
    return [zone for zone in zones if zone.polygon.contains(point)]


def zone_problems(
    *,
    zone_type: str,
    vertices: Any,
    max_speed: Any = None,
    direction: Any = None,
    limitation: Any = "",
    penalty_factor: Any = None,
    priority_factor: Any = None,
    release_loss_behavior: Any = "",
) -> list[tuple[str, str]]:
    """(field, message) for every problem of one zone's data; [] when it is fine.

    The rules are VDA 5050 3.0's (zoneSet schema and §6.4): at least three vertices forming a
    simple polygon, and the fields each zone type requires.
    """
    problems = _vertex_problems(vertices)
    if zone_type == SPEED_LIMIT and not _positive(max_speed):
        problems.append(("max_speed", "a speed limit zone needs a speed above 0 m/s"))
    if zone_type in LIMITATIONS:
        if not _number(direction):
            problems.append(("direction", "needs a direction of travel (rad)"))
        if limitation not in LIMITATIONS[zone_type]:
            allowed = ", ".join(LIMITATIONS[zone_type])
            problems.append(("limitation", f"must be one of {allowed}"))
    if zone_type == PENALTY and not _unit(penalty_factor):
        problems.append(("penalty_factor", "a penalty zone needs a factor from 0 to 1"))
    if zone_type == PRIORITY and not _unit(priority_factor):
        problems.append(("priority_factor", "a priority zone needs a factor from 0 to 1"))
    if zone_type == RELEASE and release_loss_behavior not in RELEASE_LOSS:
        problems.append(("release_loss_behavior", f"must be one of {', '.join(RELEASE_LOSS)}"))
    return problems


def _vertex_problems(vertices: Any) -> list[tuple[str, str]]:
    if not isinstance(vertices, list) or not all(
        isinstance(v, dict) and _number(v.get("x")) and _number(v.get("y")) for v in vertices
    ):
        return [("vertices", "must be a list of points {x, y} in metres")]
    try:
        polygon = Polygon.of((v["x"], v["y"]) for v in vertices)
    except ValueError:
        return [("vertices", "needs at least three different points")]
    if polygon.area < 1e-6:
        return [("vertices", "the points lie on one line: the zone has no area")]
    crossing = self_intersections(polygon.vertices)
    if crossing:
        i, j = crossing[0]
        return [("vertices", f"sides {i + 1} and {j + 1} cross: draw a simple polygon")]
    return []


def _apply(
    edge: GraphEdge, nodes: Mapping[str, GraphNode], by_map: Mapping[str, list[ZoneRule]]
) -> GraphEdge | None:
    start, end = nodes.get(edge.start), nodes.get(edge.end)
    if start is None or end is None:
        return edge
    if start.map_id != end.map_id:
        return _transition(edge, end, by_map.get(end.map_id, []))
    a, b = (start.x, start.y), (end.x, end.y)
    length = math.dist(a, b)
    heading = math.atan2(b[1] - a[1], b[0] - a[0]) if length > 0 else None
    max_speed, factor, rules = edge.max_speed, edge.cost_factor, edge.rules
    for zone in by_map.get(start.map_id, []):
        if zone.zone_type in CLOSING:
            if _enters(zone, a, b):
                if zone.zone_type == BLOCKED or not zone.vehicle_types:
                    return None
                rules = _only(rules, zone.vehicle_types)
                if not rules:
                    return None
            continue
        inside = zone.polygon.length_inside(a, b)
        if inside < MIN_INSIDE:
            continue
        share = min(1.0, inside / length)
        if zone.zone_type == SPEED_LIMIT and zone.max_speed:
            max_speed = min(max_speed, zone.max_speed) if max_speed else zone.max_speed
        elif zone.zone_type == DIRECTED and zone.direction is not None and heading is not None:
            if angle_between(heading, zone.direction) > AGAINST:
                if zone.limitation != SOFT:
                    return None
                factor *= 1.0 + share * (DIRECTED_SOFT_FACTOR - 1.0)
        elif zone.zone_type == PENALTY and zone.penalty_factor is not None:
            factor *= 1.0 + share * (penalty_multiplier(zone.penalty_factor) - 1.0)
        elif zone.zone_type == PRIORITY and zone.priority_factor is not None:
            factor *= 1.0 - share * (1.0 - priority_multiplier(zone.priority_factor))
    if (max_speed, factor, rules) == (edge.max_speed, edge.cost_factor, edge.rules):
        return edge
    return replace(edge, max_speed=max_speed, cost_factor=factor, rules=rules)


def _transition(edge: GraphEdge, end: GraphNode, zones: list[ZoneRule]) -> GraphEdge | None:
    rules = edge.rules
    for zone in zones:
        if zone.zone_type in CLOSING and zone.polygon.contains((end.x, end.y)):
            if zone.zone_type == BLOCKED or not zone.vehicle_types:
                return None
            rules = _only(rules, zone.vehicle_types)
            if not rules:
                return None
    return edge if rules is edge.rules else replace(edge, rules=rules)


def _enters(zone: ZoneRule, a: tuple[float, float], b: tuple[float, float]) -> bool:
    """Whether an edge from a to b drives into or within the zone (not: out of it)."""
    polygon = zone.polygon
    if polygon.contains(a):
        return polygon.contains(b)
    return polygon.contains(b) or polygon.length_inside(a, b) >= MIN_INSIDE


def _only(rules: Mapping[str, EdgeRule], allowed: frozenset[str]) -> Mapping[str, EdgeRule]:
    """Edge rules for the allowed vehicle types only (an open edge opens to exactly those)."""
    if not rules:
        return {vehicle_type: EdgeRule() for vehicle_type in sorted(allowed)}
    return {t: rule for t, rule in rules.items() if t in allowed}


def _closed_to_all(zone: ZoneRule) -> bool:
    return zone.zone_type == RESTRICTED and not zone.vehicle_types


def _number(value: Any) -> bool:
    return isinstance(value, int | float) and not isinstance(value, bool) and math.isfinite(value)


def _positive(value: Any) -> bool:
    return _number(value) and value > 0


def _unit(value: Any) -> bool:
    return _number(value) and 0.0 <= value <= 1.0
