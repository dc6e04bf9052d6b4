"""Helpers for the maps tests: the official LIF examples, small LIF files, model snapshots."""

import json
from pathlib import Path
from typing import Any

from django.db.models import Model

from maps.models import (
    Edge,
    EdgeProperty,
    Layout,
    LifImport,
    Map,
    Node,
    NodeProperty,
    Site,
    Station,
    StationNode,
    VehicleType,
)

EXAMPLES = Path(__file__).resolve().parents[3] / "shared" / "lif" / "examples" / "1.0.0"
EXAMPLE_FILES = sorted(EXAMPLES.glob("*.json"))
MODELS: list[type[Model]] = [
    Site,
    Map,
    LifImport,
    Layout,
    VehicleType,
    Node,
    NodeProperty,
    Edge,
    EdgeProperty,
    Station,
    StationNode,
]


def example(prefix: str) -> dict[str, Any]:
    """The official example whose file name starts with `prefix` (e.g. "10.14_")."""
    (path,) = [p for p in EXAMPLE_FILES if p.name.startswith(prefix)]
    return json.loads(path.read_text())


def row_counts() -> dict[str, int]:
    return {model.__name__: model.objects.count() for model in MODELS}


def lif(
    nodes: list[tuple[str, float, float]],
    edges: list[tuple[str, str]],
    stations: list[tuple[str, list[str], str]] = (),  # type: ignore[assignment]
    *,
    map_id: str = "M1",
    project: str = "test",
    types: dict[str, list[str]] | None = None,
    props: dict[str, dict[str, Any]] | None = None,
) -> dict[str, Any]:
    """A small LIF file. Edges are "a-b" between a and b. `types` maps element ids to the vehicle
    types allowed there (default: "AGV" everywhere); `props` adds edge property fields."""
    types, props = types or {}, props or {}

    def node_props(node_id: str) -> list[dict[str, Any]]:
        return [{"vehicleTypeId": t} for t in types.get(node_id, ["AGV"])]

    def edge_props(edge_id: str) -> list[dict[str, Any]]:
        extra = props.get(edge_id, {})
        return [
            {"vehicleTypeId": t, "rotationAllowed": False, **extra}
            for t in types.get(edge_id, ["AGV"])
        ]

    return {
        "metaInformation": {
            "projectIdentification": project,
            "creator": "tests",
            "exportTimestamp": "2026-11-23T08:00:00.00Z",
            "lifVersion": "1.0.0",
        },
        "layouts": [
            {
                "layoutId": f"L-{map_id}",
                "layoutVersion": "1",
                "nodes": [
                    {
                        "nodeId": n,
                        "mapId": map_id,
                        "nodePosition": {"x": x, "y": y},
                        "vehicleTypeNodeProperties": node_props(n),
                    }
                    for n, x, y in nodes
                ],
                "edges": [
                    {
                        "edgeId": f"{a}-{b}",
                        "startNodeId": a,
                        "endNodeId": b,
                        "vehicleTypeEdgeProperties": edge_props(f"{a}-{b}"),
                    }
                    for a, b in edges
                ],
                "stations": [
                    {"stationId": s, "interactionNodeIds": ns, "openFleet": {"kind": kind}}
                    for s, ns, kind in stations
                ],
            }
        ],
    }


def snapshot(site: Site) -> dict[str, list[tuple[Any, ...]]]:
    """The site's layout in a normalised, comparable form (no database keys, sorted)."""

    def js(value: Any) -> str:
        return json.dumps(value, sort_keys=True)

    nodes = Node.objects.filter(map__site=site).select_related("map", "layout")
    edges = Edge.objects.filter(map__site=site).select_related("map", "layout", "start", "end")
    stations = Station.objects.filter(map__site=site).select_related("map", "layout", "node")
    return {
        "maps": sorted(
            (m.map_id, m.name, m.level, m.source_id) for m in Map.objects.filter(site=site)
        ),
        "layouts": sorted(
            (la.layout_id, la.name, la.version, la.level_id, la.description, la.position)
            for la in Layout.objects.filter(site=site)
        ),
        "nodes": sorted(
            (
                n.node_id,
                n.map.map_id,
                n.layout and n.layout.layout_id,
                n.x,
                n.y,
                n.theta,
                n.name,
                n.description,
            )
            for n in nodes
        ),
        "node_properties": sorted(
            (p.node.node_id, p.vehicle_type.type_id, p.theta, js(p.actions))
            for p in NodeProperty.objects.filter(node__in=nodes).select_related(
                "node", "vehicle_type"
            )
        ),
        "edges": sorted(
            (
                e.edge_id,
                e.map.map_id,
                e.layout and e.layout.layout_id,
                e.start.node_id,
                e.end.node_id,
                round(e.length, 9),
                e.max_speed,
                e.name,
                e.description,
            )
            for e in edges
        ),
        "edge_properties": sorted(
            (
                p.edge.edge_id,
                p.vehicle_type.type_id,
                p.vehicle_orientation,
                p.orientation_type,
                p.rotation_allowed,
                p.rotation_at_start,
                p.rotation_at_end,
                p.max_speed,
                p.max_rotation_speed,
                p.min_height,
                p.max_height,
                p.load_unloaded,
                p.load_loaded,
                js(p.load_set_names),
                js(p.actions),
                js(p.trajectory),
                p.reentry_allowed,
            )
            for p in EdgeProperty.objects.filter(edge__in=edges).select_related(
                "edge", "vehicle_type"
            )
        ),
        "stations": sorted(
            (
                s.station_id,
                s.map.map_id,
                s.layout and s.layout.layout_id,
                s.kind,
                s.node.node_id,
                s.name,
                s.description,
                s.height,
                s.position_x,
                s.position_y,
                s.position_theta,
            )
            for s in stations
        ),
        "station_nodes": sorted(
            (sn.station.station_id, sn.position, sn.node.node_id)
            for sn in StationNode.objects.filter(station__in=stations).select_related(
                "station", "node"
            )
        ),
    }


def wipe(site: Site) -> None:
    """Delete a site with everything in it (stations first: nodes are protected by them)."""
    Station.objects.filter(map__site=site).delete()
    Map.objects.filter(site=site).delete()
    site.delete()
