"""Routing graphs of maps and sites: rows converted to `traffic` data, cached per revision.

Enabled zones shape the graph (`maps.zoning.apply_zones`): edges into blocked zones and against
one-way zones are left out, speed limit zones lower edge limits, penalty and priority zones scale
edge costs. Zone writes bump the revision like every other layout change.

A graph is cached under the revision (and last change time) of every map it covers; services bump
the revision on every layout change (`maps.services.mark_layout_changed`), so the next load builds
a fresh graph with empty distance tables. Each process keeps its own small cache.
"""

import threading
from collections import OrderedDict
from collections.abc import Callable, Hashable
from typing import Any

from django.db.models import QuerySet

from maps.lif.properties import nurbs_of
from maps.models import Edge, EdgeProperty, Map, Node, NodeProperty, Site, VehicleType
from maps.selectors.zones import zone_rules
from maps.zoning import apply_zones
from traffic import EdgeRule, GraphEdge, GraphNode, NodeRule, RoutingGraph, VehicleProfile
from traffic.costs import BOTH, DEFAULT_SPEED

CACHE_SIZE = 16
_cache: OrderedDict[Hashable, RoutingGraph] = OrderedDict()
_lock = threading.Lock()


def load_graph(*, map: Map) -> RoutingGraph:
    """The routing graph of `map` alone (edges to other floors left out); cached."""
    maps = Map.objects.filter(pk=map.pk)
    return _cached(("map", map.pk, *_versions(maps)), lambda: _build(maps))


def load_site_graph(*, site: Site) -> RoutingGraph:
    """The routing graph of every map of `site`, with the transitions between floors; cached."""
    maps = Map.objects.filter(site=site)
    return _cached(("site", site.pk, *_versions(maps)), lambda: _build(maps))


def load_graph_for_routing(*, map: Map) -> RoutingGraph:
    """The site graph when `map` belongs to a site (routes may change floors), else the map's."""
    return load_site_graph(site=map.site) if map.site is not None else load_graph(map=map)


def vehicle_profile(
    *, vehicle_type: VehicleType | None, loaded: bool | None = None, load_set: str | None = None
) -> VehicleProfile:
    """The routing profile of a vehicle type (None: any vehicle) carrying a load or not."""
    if vehicle_type is None:
        return VehicleProfile(loaded=loaded, load_set=load_set)
    return VehicleProfile(
        vehicle_type=vehicle_type.type_id,
        max_speed=vehicle_type.max_speed or DEFAULT_SPEED,
        rotation_speed=vehicle_type.rotation_speed,
        loaded=loaded,
        load_set=load_set,
        height=vehicle_type.height,
    )


def edge_speed_limits(
    *, map: Map, vehicle_type: VehicleType | None = None
) -> dict[str, float | None]:
    """Edge id → speed limit (m/s, None: no limit) of every edge of `map` vehicles may drive
    (transitions to other floors included).

    The limit is the edge's own, lowered by the speed limit zones it runs through and, for a
    vehicle type, by that type's LIF edge property. Edges a zone closes are left out. This is
    the `maxSpeed` to put into a VDA 5050 order's edges.
    """
    graph = load_graph_for_routing(map=map)
    limits: dict[str, float | None] = {}
    for edge in graph.edges:
        if graph.nodes[edge.start].map_id != map.map_id:
            continue
        limit = edge.max_speed
        if vehicle_type is not None and edge.rules:
            rule = edge.rules.get(vehicle_type.type_id)
            if rule is not None and rule.max_speed is not None:
                limit = min(limit, rule.max_speed) if limit is not None else rule.max_speed
        limits[edge.edge_id] = limit
    return limits


def clear_graph_cache() -> None:
    """Forget every cached graph (tests, or after bulk writes that bypass the services)."""
    with _lock:
        _cache.clear()


def _versions(maps: QuerySet[Map]) -> tuple[Any, ...]:
    return tuple(maps.order_by("pk").values_list("pk", "revision", "updated_at"))


def _cached(key: Hashable, build: Callable[[], RoutingGraph]) -> RoutingGraph:
    with _lock:
        graph = _cache.get(key)
        if graph is not None:
            _cache.move_to_end(key)
            return graph
    graph = build()
    with _lock:
        _cache[key] = graph
        if len(_cache) > CACHE_SIZE:
            _cache.popitem(last=False)
    return graph


def _build(maps: QuerySet[Map]) -> RoutingGraph:
    node_rules: dict[int, dict[str, NodeRule]] = {}
    for node_pk, type_id, theta in NodeProperty.objects.filter(node__map__in=maps).values_list(
        "node_id", "vehicle_type__type_id", "theta"
    ):
        node_rules.setdefault(node_pk, {})[type_id] = NodeRule(theta=theta)
    nodes: dict[str, GraphNode] = {}
    for pk, node_id, x, y, theta, map_id in (
        Node.objects.filter(map__in=maps)
        .order_by("map__map_id", "pk")
        .values_list("pk", "node_id", "x", "y", "theta", "map__map_id")
    ):
        if node_id not in nodes:  # ids are unique per site; validation reports duplicates
            nodes[node_id] = GraphNode(node_id, x, y, map_id, theta, node_rules.get(pk, {}))
    edge_rules: dict[int, dict[str, EdgeRule]] = {}
    for row in EdgeProperty.objects.filter(edge__map__in=maps).values(*RULE_FIELDS):
        edge_rules.setdefault(row["edge_id"], {})[row["vehicle_type__type_id"]] = edge_rule(row)
    edges = [
        GraphEdge(edge_id, start, end, length, max_speed, edge_rules.get(pk, {}))
        for pk, edge_id, start, end, length, max_speed in Edge.objects.filter(map__in=maps)
        .order_by("pk")
        .values_list("pk", "edge_id", "start__node_id", "end__node_id", "length", "max_speed")
    ]
    return RoutingGraph(nodes.values(), apply_zones(nodes, edges, zone_rules(maps=maps)))


RULE_FIELDS = (
    "edge_id",
    "vehicle_type__type_id",
    "max_speed",
    "max_rotation_speed",
    "vehicle_orientation",
    "orientation_type",
    "rotation_allowed",
    "rotation_at_start",
    "rotation_at_end",
    "load_unloaded",
    "load_loaded",
    "load_set_names",
    "max_height",
    "trajectory",
)


def edge_rule(row: dict[str, Any]) -> EdgeRule:
    """The routing rule of one EdgeProperty row (as `values(*RULE_FIELDS)` gives it)."""
    trajectory = None
    if row["trajectory"]:
        try:
            trajectory = nurbs_of(row["trajectory"])
        except (ValueError, KeyError, TypeError):
            trajectory = None  # a broken trajectory edited by hand: drive the straight line
    return EdgeRule(
        max_speed=row["max_speed"],
        max_rotation_speed=row["max_rotation_speed"],
        orientation=row["vehicle_orientation"],
        orientation_global=row["orientation_type"] == EdgeProperty.Orientation.GLOBAL,
        rotation_allowed=row["rotation_allowed"],
        rotation_at_start=row["rotation_at_start"] or BOTH,
        rotation_at_end=row["rotation_at_end"] or BOTH,
        unloaded=row["load_unloaded"] is not False,
        loaded=row["load_loaded"] is not False,
        load_sets=frozenset(row["load_set_names"] or ()),
        max_height=row["max_height"],
        trajectory=trajectory,
    )
