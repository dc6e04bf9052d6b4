"""Writing maps out as a LIF 1.0 file (plain data, ready for JSON).

Elements keep the LIF layout they were imported in; elements made here (the demo, the admin) go
to one layout per map, named after it. What LIF has no field for goes into an `openFleet` object
(station kind, a node heading or an edge speed limit for every vehicle, and a layout's zones in
VDA 5050 3.0 form), which our importer reads back and other readers may ignore. Only edges whose
both nodes are exported are written: export a whole site to keep transitions between floors.
"""

from collections.abc import Sequence
from datetime import UTC, datetime
from typing import Any

from django.db.models import Prefetch

from maps.lif.parse import EXTENSION
from maps.models import (
    Edge,
    EdgeProperty,
    Layout,
    Map,
    Node,
    NodeProperty,
    Station,
    StationNode,
    Zone,
)

LIF_VERSION = "1.0.0"
CREATOR = "Open Fleet"


def export_lif(*, maps: Sequence[Map], project: str = "") -> dict[str, Any]:
    """The LIF document of `maps` (their nodes, edges between them, stations, layouts)."""
    maps = list(maps)
    groups: dict[Any, dict[str, Any]] = {}
    nodes = (
        Node.objects.filter(map__in=maps)
        .select_related("map", "layout")
        .prefetch_related(
            Prefetch("properties", NodeProperty.objects.select_related("vehicle_type"))
        )
        .order_by("layout__position", "pk")
    )
    for node in nodes:
        _group(groups, node.layout, node.map)["nodes"].append(_node(node))
    edges = (
        Edge.objects.filter(start__map__in=maps, end__map__in=maps)
        .select_related("start__map", "end", "layout")
        .prefetch_related(
            Prefetch("properties", EdgeProperty.objects.select_related("vehicle_type"))
        )
        .order_by("pk")
    )
    for edge in edges:
        _group(groups, edge.layout, edge.start.map)["edges"].append(_edge(edge))
    stations = (
        Station.objects.filter(map__in=maps)
        .select_related("map", "layout", "node")
        .prefetch_related(Prefetch("station_nodes", StationNode.objects.select_related("node")))
        .order_by("pk")
    )
    for station in stations:
        _group(groups, station.layout, station.map)["stations"].append(_station(station))
    _zones(groups, maps)
    ordered = sorted(groups.items(), key=lambda item: _order(item[0]))
    return {
        "metaInformation": {
            "projectIdentification": project or _project(maps),
            "creator": CREATOR,
            "exportTimestamp": datetime.now(UTC).strftime("%Y-%m-%dT%H:%M:%S.%fZ"),
            "lifVersion": LIF_VERSION,
        },
        "layouts": [layout for _, layout in ordered],
    }


def _group(groups: dict[Any, dict[str, Any]], layout: Layout | None, map: Map) -> dict[str, Any]:
    key: Any = layout if layout is not None else map
    if key not in groups:
        if layout is not None:
            head = _optional(
                layoutId=layout.layout_id,
                layoutName=layout.name,
                layoutVersion=layout.version or "1",
                layoutLevelId=layout.level_id,
                layoutDescription=layout.description,
            )
        else:
            head = _optional(
                layoutId=map.map_id,
                layoutName=map.name,
                layoutVersion=str(map.revision + 1),
                layoutLevelId=map.level,
                layoutDescription=map.description,
            )
        groups[key] = {**head, "nodes": [], "edges": [], "stations": []}
    return groups[key]


def _zones(groups: dict[Any, dict[str, Any]], maps: list[Map]) -> None:
    """Each map's zones go into the `openFleet` object of the first layout with its nodes."""
    zones = (
        Zone.objects.filter(map__in=maps)
        .select_related("map")
        .prefetch_related("vehicle_types")
        .order_by("map__map_id", "zone_id")
    )
    first: dict[str, dict[str, Any]] = {}
    for group in groups.values():
        for node in group["nodes"]:
            first.setdefault(node["mapId"], group)
    for zone in zones:
        group = first.get(zone.map.map_id) or _group(groups, None, zone.map)
        group.setdefault(EXTENSION, {}).setdefault("zones", []).append(zone_to_lif(zone))


def zone_to_lif(zone: Zone) -> dict[str, Any]:
    """A zone in VDA 5050 3.0 names (zoneId, zoneType, vertices, ...) plus mapId and ours."""
    limitation = {}
    if zone.limitation and zone.zone_type in ("DIRECTED", "BIDIRECTED"):
        key = "directedLimitation" if zone.zone_type == "DIRECTED" else "bidirectedLimitation"
        limitation[key] = zone.limitation
    actions = {}
    if zone.zone_type == "ACTION":
        actions = {
            "entryActions": zone.entry_actions,
            "duringActions": zone.during_actions,
            "exitActions": zone.exit_actions,
        }
    data = {
        "zoneId": zone.zone_id,
        "zoneType": zone.zone_type,
        "mapId": zone.map.map_id,
        "enabled": zone.enabled,
        "vertices": [{"x": v["x"], "y": v["y"]} for v in zone.vertices],
    }
    data |= _optional(
        zoneDescriptor=zone.name,
        zoneDescription=zone.description,
        maximumSpeed=zone.max_speed,
        direction=zone.direction,
        penaltyFactor=zone.penalty_factor,
        priorityFactor=zone.priority_factor,
        releaseLossBehavior=zone.release_loss_behavior,
        vehicleTypeIds=sorted(t.type_id for t in zone.vehicle_types.all()),
    )
    return data | limitation | actions


def _order(key: Any) -> tuple[int, int, str]:
    if isinstance(key, Layout):
        return (0, key.position, key.layout_id)
    return (1, 0, key.map_id)


def _project(maps: list[Map]) -> str:
    imports = {m.lif_import.project if m.lif_import else "" for m in maps}
    if len(imports) == 1 and (project := imports.pop()):
        return project
    sites = {str(m.site) for m in maps if m.site is not None}
    return sites.pop() if len(sites) == 1 else "Open Fleet layout"


def _node(node: Node) -> dict[str, Any]:
    props = [
        _optional(vehicleTypeId=p.vehicle_type.type_id, theta=p.theta, actions=p.actions)
        for p in node.properties.all()
    ]
    data = _optional(nodeId=node.node_id, nodeName=node.name, nodeDescription=node.description)
    data |= {
        "mapId": node.map.map_id,
        "nodePosition": {"x": node.x, "y": node.y},
        "vehicleTypeNodeProperties": props,
    }
    if not props and node.theta is not None:
        data[EXTENSION] = {"theta": node.theta}
    return data


def _edge(edge: Edge) -> dict[str, Any]:
    data = _optional(edgeId=edge.edge_id, edgeName=edge.name, edgeDescription=edge.description)
    data |= {
        "startNodeId": edge.start.node_id,
        "endNodeId": edge.end.node_id,
        "vehicleTypeEdgeProperties": [_edge_property(p) for p in edge.properties.all()],
    }
    if edge.max_speed is not None:
        data[EXTENSION] = {"maxSpeed": edge.max_speed}
    return data


def _edge_property(p: EdgeProperty) -> dict[str, Any]:
    load = None
    if p.load_unloaded is not None or p.load_loaded is not None:
        load = {"unloaded": bool(p.load_unloaded), "loaded": bool(p.load_loaded)}
        if p.load_set_names is not None:
            load["loadSetNames"] = p.load_set_names
    return _optional(
        vehicleTypeId=p.vehicle_type.type_id,
        vehicleOrientation=p.vehicle_orientation,
        orientationType=p.orientation_type,
        rotationAllowed=p.rotation_allowed,
        rotationAtStartNodeAllowed=p.rotation_at_start,
        rotationAtEndNodeAllowed=p.rotation_at_end,
        maxSpeed=p.max_speed,
        maxRotationSpeed=p.max_rotation_speed,
        minHeight=p.min_height,
        maxHeight=p.max_height,
        loadRestriction=load,
        actions=p.actions,
        trajectory=p.trajectory,
        reentryAllowed=p.reentry_allowed,
    )


def _station(station: Station) -> dict[str, Any]:
    node_ids = [sn.node.node_id for sn in station.station_nodes.all()] or [station.node.node_id]
    position = None
    if station.position_x is not None and station.position_y is not None:
        position = _optional(
            x=station.position_x, y=station.position_y, theta=station.position_theta
        )
    data: dict[str, Any] = {"stationId": station.station_id, "interactionNodeIds": node_ids}
    data |= _optional(
        stationName=station.name,
        stationDescription=station.description,
        stationHeight=station.height,
        stationPosition=position,
    )
    data[EXTENSION] = {"kind": station.kind}
    return data


def _optional(**fields: Any) -> dict[str, Any]:
    """`fields` without the empty ones (None, "", []): LIF leaves unset optional fields out."""
    return {k: v for k, v in fields.items() if v is not None and v != "" and v != []}
