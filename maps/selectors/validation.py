"""Layout validation: what keeps vehicles from reaching places, and what will jam traffic.

Findings per map (reachability is judged on the site graph, so lifts to other floors count):

errors    unreachable-node, dead-end, station-off-graph, duplicate-node-id,
          station-in-blocked-zone, invalid-zone
warnings  missing-reverse, overlapping-nodes, vehicle-type-cannot-reach-station,
          station-on-aisle, charger-on-aisle, parking-on-aisle, trajectory-mismatch, empty-map,
          station-in-no-stopping-zone, parking-outside-parking-area,
          charger-outside-charging-area, directed-zones-overlap
info      node-in-blocked-zone (such nodes are not reported as unreachable)
"""

import math
from collections import defaultdict
from dataclasses import asdict, dataclass
from typing import Any, Literal

from maps.models import EdgeProperty, Map, Node, Station, StationNode, Zone
from maps.selectors.graph import load_graph_for_routing
from maps.selectors.zones import zone_rules
from maps.zoning import (
    BIDIRECTED,
    CHARGING,
    DIRECTED,
    NO_STOPPING,
    PARKING,
    ZoneRule,
    closed_nodes,
    zone_problems,
    zones_at,
)
from traffic import RoutingGraph, VehicleProfile
from traffic.reachability import Reachability, analyse

OVERLAP = 0.05  # m: nodes closer than this look like one place
TRAJECTORY_GAP = 0.1  # m: allowed gap between a trajectory's ends and its nodes
SEVERITY_ORDER = {"error": 0, "warning": 1, "info": 2}
ON_AISLE: dict[str, str] = {"CHARGE": "charger-on-aisle", "PARK": "parking-on-aisle"}


@dataclass(frozen=True)
class Finding:
    """One problem of a layout: severity, a stable code, the object concerned, a message."""

    severity: Literal["error", "warning", "info"]
    code: str
    object_type: str
    object_id: str
    message: str

    def as_dict(self) -> dict[str, Any]:
        return asdict(self)

    def __str__(self) -> str:
        return f"{self.severity}: {self.code} {self.object_type} {self.object_id}: {self.message}"


def validate_layout(*, map: Map) -> list[Finding]:
    """Every finding for `map`, errors first. The demo warehouse has none."""
    node_ids = set(Node.objects.filter(map=map).values_list("node_id", flat=True))
    if not node_ids:
        return [Finding("warning", "empty-map", "map", map.map_id, "the map has no nodes")]
    graph = load_graph_for_routing(map=map)
    stations = _stations(map)
    reach = analyse(graph)
    zones = zone_rules(maps=Map.objects.filter(pk=map.pk))
    closed = closed_nodes((graph.nodes[n] for n in node_ids if n in graph.nodes), zones)
    open_ids = node_ids - closed.keys()
    open_stations = [s for s in stations if not set(s[2]) <= closed.keys()]
    findings = [
        *_duplicates(map, node_ids),
        *_reachability(graph, reach, open_ids),
        *_one_way(graph, reach, open_ids),
        *_stations_off_graph(reach, open_stations),
        *_overlaps(graph, node_ids),
        *_vehicle_types(graph, open_ids, [s for s in open_stations if set(s[2]) & reach.main]),
        *_on_aisles(graph, stations),
        *_trajectories(map, graph),
        *_closed(closed, stations),
        *_zone_areas(graph, zones, stations),
        *_zone_data(map),
        *_directed_overlaps(zones),
    ]
    return sorted(findings, key=lambda f: (SEVERITY_ORDER[f.severity], f.code, f.object_id))


def _stations(map: Map) -> list[tuple[str, str, list[str]]]:
    """(station id, kind, interaction node ids) of the map's stations."""
    nodes: dict[int, list[str]] = defaultdict(list)
    rows = StationNode.objects.filter(station__map=map)
    for station_pk, node_id in rows.order_by("position").values_list("station_id", "node__node_id"):
        nodes[station_pk].append(node_id)
    return [
        (station_id, kind, nodes.get(pk) or [primary])
        for pk, station_id, kind, primary in Station.objects.filter(map=map).values_list(
            "pk", "station_id", "kind", "node__node_id"
        )
    ]


def _duplicates(map: Map, node_ids: set[str]) -> list[Finding]:
    if map.site_id is None:
        return []
    others = Node.objects.filter(map__site_id=map.site_id, node_id__in=node_ids).exclude(map=map)
    return [
        Finding("error", "duplicate-node-id", "node", node_id, f"also on map {other}")
        for node_id, other in others.values_list("node_id", "map__map_id")
    ]


def _reachability(graph: RoutingGraph, reach: Reachability, node_ids: set[str]) -> list[Finding]:
    findings = []
    for node_id in sorted(node_ids & reach.unreachable):
        findings.append(
            Finding(
                "error",
                "unreachable-node",
                "node",
                node_id,
                "no route leads here from the rest of the layout",
            )
        )
    leaving = {e.start for e in graph.edges}
    for node_id in sorted(node_ids & reach.dead_ends):
        why = "no edge leaves it" if node_id not in leaving else "no route leads back from it"
        findings.append(
            Finding(
                "error", "dead-end", "node", node_id, f"a vehicle that drives here is stuck: {why}"
            )
        )
    return findings


def _one_way(graph: RoutingGraph, reach: Reachability, node_ids: set[str]) -> list[Finding]:
    pairs = {(e.start, e.end) for e in graph.edges}
    return [
        Finding(
            "warning",
            "missing-reverse",
            "edge",
            e.edge_id,
            f"one-way from {e.start} to {e.end} with no way back; add the edge {e.end} → {e.start}",
        )
        for e in graph.edges
        if e.start in node_ids
        and (e.end, e.start) not in pairs
        and not reach.way_back(e.start, e.end)
    ]


def _stations_off_graph(
    reach: Reachability, stations: list[tuple[str, str, list[str]]]
) -> list[Finding]:
    findings = []
    for station_id, _, nodes in stations:
        off = [n for n in nodes if n not in reach.main]
        if len(off) == len(nodes):
            findings.append(
                Finding(
                    "error",
                    "station-off-graph",
                    "station",
                    station_id,
                    f"vehicles cannot drive to and away from it (node {', '.join(off)})",
                )
            )
    return findings


def _overlaps(graph: RoutingGraph, node_ids: set[str]) -> list[Finding]:
    cells: dict[tuple[int, int], list[str]] = defaultdict(list)
    joined = {frozenset((e.start, e.end)) for e in graph.edges}
    findings = []
    for node_id in sorted(node_ids):
        node = graph.nodes[node_id]
        cx, cy = math.floor(node.x / OVERLAP), math.floor(node.y / OVERLAP)
        for dx in (-1, 0, 1):
            for dy in (-1, 0, 1):
                for other_id in cells.get((cx + dx, cy + dy), []):
                    other = graph.nodes[other_id]
                    close = math.dist((node.x, node.y), (other.x, other.y)) < OVERLAP
                    if close and frozenset((node_id, other_id)) not in joined:
                        findings.append(
                            Finding(
                                "warning",
                                "overlapping-nodes",
                                "node",
                                node_id,
                                f"at the same place as node {other_id} but not joined by an edge",
                            )
                        )
        cells[(cx, cy)].append(node_id)
    return findings


def _vehicle_types(
    graph: RoutingGraph, node_ids: set[str], stations: list[tuple[str, str, list[str]]]
) -> list[Finding]:
    """Stations (on the graph for some vehicle) a vehicle type may use but cannot get to."""
    types = sorted(
        {t for n in node_ids for t in graph.nodes[n].rules}
        | {t for e in graph.edges if e.start in node_ids for t in e.rules}
    )
    findings = []
    for vehicle_type in types:
        profile = VehicleProfile(vehicle_type=vehicle_type)
        reach = analyse(graph, profile)
        for station_id, _, nodes in stations:
            usable = [n for n in nodes if graph.nodes[n].usable_by(profile)]
            if usable and not any(n in reach.main for n in usable):
                findings.append(
                    Finding(
                        "warning",
                        "vehicle-type-cannot-reach-station",
                        "station",
                        station_id,
                        f"vehicle type {vehicle_type} may use node {', '.join(usable)} "
                        "but cannot drive there and away again",
                    )
                )
    return findings


def _on_aisles(graph: RoutingGraph, stations: list[tuple[str, str, list[str]]]) -> list[Finding]:
    neighbours: dict[str, set[str]] = defaultdict(set)
    for e in graph.edges:
        neighbours[e.start].add(e.end)
        neighbours[e.end].add(e.start)
    findings = []
    for station_id, kind, nodes in stations:
        for node_id in nodes:
            around = sorted(neighbours[node_id])
            if len(around) >= 2:
                findings.append(
                    Finding(
                        "warning",
                        ON_AISLE.get(kind, "station-on-aisle"),
                        "station",
                        station_id,
                        f"a vehicle at node {node_id} stands in a through aisle "
                        f"({', '.join(around[:4])}); put the station on a spur",
                    )
                )
    return findings


def _trajectories(map: Map, graph: RoutingGraph) -> list[Finding]:
    findings = []
    rows = EdgeProperty.objects.filter(edge__map=map, trajectory__isnull=False).values_list(
        "edge__edge_id",
        "edge__start__node_id",
        "edge__end__node_id",
        "vehicle_type__type_id",
        "trajectory",
    )
    for edge_id, start, end, vehicle_type, trajectory in rows:
        points = (trajectory or {}).get("controlPoints") or []
        if not points or start not in graph.nodes or end not in graph.nodes:
            continue
        a, b = graph.nodes[start], graph.nodes[end]
        gap = max(
            math.dist((points[0]["x"], points[0]["y"]), (a.x, a.y)),
            math.dist((points[-1]["x"], points[-1]["y"]), (b.x, b.y)),
        )
        if gap > TRAJECTORY_GAP:
            findings.append(
                Finding(
                    "warning",
                    "trajectory-mismatch",
                    "edge",
                    edge_id,
                    f"the trajectory for {vehicle_type} ends {gap:.2f} m from the edge's nodes",
                )
            )
    return findings


def _closed(closed: dict[str, str], stations: list[tuple[str, str, list[str]]]) -> list[Finding]:
    """Nodes and stations inside zones no vehicle may enter."""
    findings = [
        Finding(
            "info",
            "node-in-blocked-zone",
            "node",
            node_id,
            f"inside zone {zone_id}: no vehicle drives here while the zone is enabled",
        )
        for node_id, zone_id in sorted(closed.items())
    ]
    for station_id, _, nodes in stations:
        if set(nodes) <= closed.keys():
            zone_ids = ", ".join(sorted({closed[n] for n in nodes}))
            findings.append(
                Finding(
                    "error",
                    "station-in-blocked-zone",
                    "station",
                    station_id,
                    f"unreachable: its node {', '.join(nodes)} is inside blocked zone {zone_ids}",
                )
            )
    return findings


def _zone_areas(
    graph: RoutingGraph, zones: list[ZoneRule], stations: list[tuple[str, str, list[str]]]
) -> list[Finding]:
    """Stations in no-stopping zones; parking and charging stations outside their areas."""
    by_type: dict[str, list[ZoneRule]] = defaultdict(list)
    for zone in zones:
        by_type[zone.zone_type].append(zone)
    findings = []
    for station_id, kind, nodes in stations:
        points = [(graph.nodes[n].x, graph.nodes[n].y) for n in nodes if n in graph.nodes]
        for zone_id in sorted(
            {z.zone_id for p in points for z in zones_at(p, by_type[NO_STOPPING])}
        ):
            findings.append(
                Finding(
                    "warning",
                    "station-in-no-stopping-zone",
                    "station",
                    station_id,
                    f"vehicles stop at this station, inside no-stopping zone {zone_id}",
                )
            )
        area, code = AREAS.get(kind, ("", ""))
        if area and by_type[area] and not any(zones_at(p, by_type[area]) for p in points):
            findings.append(
                Finding(
                    "warning",
                    code,
                    "station",
                    station_id,
                    f"outside every {area.lower()} zone of the map",
                )
            )
    return findings


AREAS = {
    "PARK": (PARKING, "parking-outside-parking-area"),
    "CHARGE": (CHARGING, "charger-outside-charging-area"),
}


def _zone_data(map: Map) -> list[Finding]:
    """Zones whose data breaks the rules of their type (edited around the services)."""
    findings = []
    for zone in Zone.objects.filter(map=map, enabled=True):
        for field, message in zone_problems(**zone.rule_fields()):
            findings.append(
                Finding(
                    "error",
                    "invalid-zone",
                    "zone",
                    zone.zone_id,
                    f"{field}: {message}; routing ignores what it cannot read",
                )
            )
    return findings


def _directed_overlaps(zones: list[ZoneRule]) -> list[Finding]:
    """VDA 5050 3.0: directed and bidirected zones must not overlap each other."""
    directed = [z for z in zones if z.zone_type in (DIRECTED, BIDIRECTED)]
    findings = []
    for i, first in enumerate(directed):
        for second in directed[i + 1 :]:
            if first.polygon.overlaps(second.polygon):
                findings.append(
                    Finding(
                        "warning",
                        "directed-zones-overlap",
                        "zone",
                        first.zone_id,
                        f"overlaps zone {second.zone_id}: vehicles cannot follow both directions",
                    )
                )
    return findings
