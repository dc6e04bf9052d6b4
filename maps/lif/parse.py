"""Reading a LIF file: JSON to a checked `LifDocument`, or a report of every problem.

Lenient where the official examples deviate from the official schema (warnings): a layout without
`stations`, `stationHeight` as a string, `lifVersion` "0.11.0" (the examples' pre-release number),
a node without `mapId`, an empty property list. Strict where the data could not be used (errors).
"""

import json
from collections.abc import Callable, Mapping
from typing import Any, TypeVar

from maps.lif.checks import check_references
from maps.lif.document import (
    EdgeProps,
    LifDocument,
    LifEdge,
    LifLayout,
    LifNode,
    LifStation,
    LifZone,
    NodeProps,
)
from maps.lif.properties import read_edge_props, read_node_props
from maps.lif.reader import Reader, show
from maps.lif.report import ImportReport
from maps.models import Station, Zone
from maps.zoning import ZONE_RULE_FIELDS, zone_problems

Props = TypeVar("Props", NodeProps, EdgeProps)

EXTENSION = "openFleet"  # our own fields that LIF lacks (station kind, limits for every vehicle,
# a layout's zones)
META_KEYS = ("projectIdentification", "creator", "exportTimestamp", "lifVersion")
LAYOUT_KEYS = (
    "layoutId",
    "layoutName",
    "layoutVersion",
    "layoutLevelId",
    "layoutDescription",
    "nodes",
    "edges",
    "stations",
    EXTENSION,
)
ZONE_KEYS = (
    "zoneId",
    "zoneType",
    "mapId",
    "enabled",
    "vertices",
    "zoneDescriptor",
    "zoneDescription",
    "maximumSpeed",
    "direction",
    "directedLimitation",
    "bidirectedLimitation",
    "penaltyFactor",
    "priorityFactor",
    "releaseLossBehavior",
    "entryActions",
    "duringActions",
    "exitActions",
    "vehicleTypeIds",
)
NODE_KEYS = (
    "nodeId",
    "nodeName",
    "nodeDescription",
    "mapId",
    "nodePosition",
    "vehicleTypeNodeProperties",
    EXTENSION,
)
EDGE_KEYS = (
    "edgeId",
    "edgeName",
    "edgeDescription",
    "startNodeId",
    "endNodeId",
    "vehicleTypeEdgeProperties",
    EXTENSION,
)
STATION_KEYS = (
    "stationId",
    "interactionNodeIds",
    "stationName",
    "stationDescription",
    "stationHeight",
    "stationPosition",
    EXTENSION,
)


def parse_lif(source: bytes | str | Mapping[str, Any]) -> tuple[LifDocument | None, ImportReport]:
    """The document and the report; the document is None when the report has errors."""
    report = ImportReport()
    data = _decode(source, report)
    if data is None:
        return None, report
    reader = Reader(report)
    root = reader.obj(data, "$")
    if root is None:
        return None, report
    reader.known(root, "$", "file", ("metaInformation", "layouts"))
    document = _meta(reader, root)
    for i, raw in enumerate(reader.array(root, "layouts", "$", required=True) or []):
        layout = _layout(reader, raw, f"$.layouts[{i}]")
        if layout is not None:
            document.layouts.append(layout)
    if not document.layouts and not report.errors:
        report.error("$.layouts", "no layouts")
    check_references(document, report)
    reader.flush_unknown()
    report.project = document.project
    return (None if report.errors else document), report


def _decode(source: bytes | str | Mapping[str, Any], report: ImportReport) -> Any:
    if isinstance(source, Mapping):
        return source
    if not isinstance(source, bytes | str):  # a JSON body that is a list, number or boolean
        report.error("$", f"a LIF document is a JSON object, not {type(source).__name__}")
        return None
    try:
        text = source.decode("utf-8-sig") if isinstance(source, bytes) else source
        return json.loads(text)
    except UnicodeDecodeError as exc:
        report.error("$", f"not UTF-8 text: {exc.reason} at byte {exc.start}")
    except json.JSONDecodeError as exc:
        report.error("$", f"not valid JSON: {exc.msg} at line {exc.lineno} column {exc.colno}")
    return None


def _meta(reader: Reader, root: dict[str, Any]) -> LifDocument:
    report = reader.report
    meta = reader.obj(root.get("metaInformation"), "$.metaInformation")
    if meta is None:
        return LifDocument("", "", "", "")
    path = "$.metaInformation"
    reader.known(meta, path, "metaInformation", META_KEYS)
    document = LifDocument(
        project=reader.string(meta, "projectIdentification", path, required=True),
        creator=reader.string(meta, "creator", path),
        export_timestamp=reader.string(meta, "exportTimestamp", path),
        lif_version=reader.string(meta, "lifVersion", path),
    )
    for key in ("creator", "exportTimestamp", "lifVersion"):
        if key not in meta:
            report.warn(f"{path}.{key}", "missing (LIF requires it)")
    version = document.lif_version
    major = version.split(".")[0] if version else "1"
    if not major.isdigit():
        report.warn(f"{path}.lifVersion", f"{show(version)} is not a version; read as LIF 1.0.0")
    elif int(major) > 1:
        report.error(f"{path}.lifVersion", f"LIF {version} is not supported (only 1.x)")
    elif int(major) == 0:
        report.warn(f"{path}.lifVersion", f"{version} predates LIF 1.0.0; read as 1.0.0")
    return document


def _layout(reader: Reader, raw: Any, path: str) -> LifLayout | None:
    data = reader.obj(raw, path)
    if data is None:
        return None
    reader.known(data, path, "layout", LAYOUT_KEYS)
    layout = LifLayout(
        layout_id=reader.string(data, "layoutId", path, required=True),
        version=reader.string(data, "layoutVersion", path),
        path=path,
        name=reader.string(data, "layoutName", path),
        level_id=reader.string(data, "layoutLevelId", path),
        description=reader.string(data, "layoutDescription", path),
    )
    if "layoutVersion" not in data:
        reader.report.warn(f"{path}.layoutVersion", "missing (LIF requires it)")
    for i, item in enumerate(reader.array(data, "nodes", path, required=True) or []):
        node = _node(reader, item, f"{path}.nodes[{i}]", layout.layout_id)
        if node is not None:
            layout.nodes.append(node)
    for i, item in enumerate(reader.array(data, "edges", path, required=True) or []):
        edge = _edge(reader, item, f"{path}.edges[{i}]", layout.layout_id)
        if edge is not None:
            layout.edges.append(edge)
    if "stations" not in data:
        reader.report.warn(f"{path}.stations", "missing (LIF 1.0 requires it); taken as empty")
    for i, item in enumerate(reader.array(data, "stations", path) or []):
        station = _station(reader, item, f"{path}.stations[{i}]", layout.layout_id)
        if station is not None:
            layout.stations.append(station)
    extension = _extension(reader, data, path, ("zones",))
    for i, item in enumerate(reader.array(extension, "zones", f"{path}.{EXTENSION}") or []):
        zone = _zone(reader, item, f"{path}.{EXTENSION}.zones[{i}]")
        if zone is not None:
            layout.zones.append(zone)
    return layout


def _zone(reader: Reader, raw: Any, path: str) -> LifZone | None:
    """A zone as `maps.lif.export.zone_to_lif` writes it (VDA 5050 3.0 names plus ours)."""
    data = reader.obj(raw, path)
    if data is None:
        return None
    reader.known(data, path, "zone", ZONE_KEYS)
    zone_type = reader.choice(data, "zoneType", path, Zone.Type.values, required=True)
    limitation_key = "bidirectedLimitation" if zone_type == "BIDIRECTED" else "directedLimitation"
    enabled = reader.boolean(data, "enabled", path)
    fields: dict[str, Any] = {
        "zone_type": zone_type,
        "vertices": data.get("vertices"),
        "name": reader.string(data, "zoneDescriptor", path)[:200],
        "description": reader.string(data, "zoneDescription", path),
        "enabled": True if enabled is None else enabled,
        "max_speed": reader.number(data, "maximumSpeed", path, positive=True),
        "direction": reader.number(data, "direction", path),
        "limitation": reader.choice(data, limitation_key, path, Zone.Limitation.values),
        "penalty_factor": reader.number(data, "penaltyFactor", path, minimum=0.0),
        "priority_factor": reader.number(data, "priorityFactor", path, minimum=0.0),
        "release_loss_behavior": reader.choice(
            data, "releaseLossBehavior", path, Zone.ReleaseLoss.values
        ),
        "entry_actions": reader.array(data, "entryActions", path) or [],
        "during_actions": reader.array(data, "duringActions", path) or [],
        "exit_actions": reader.array(data, "exitActions", path) or [],
    }
    zone = LifZone(
        zone_id=reader.string(data, "zoneId", path, required=True),
        map_id=reader.string(data, "mapId", path, required=True),
        zone_type=zone_type,
        path=path,
        fields=fields,
        vehicle_types=reader.strings(data, "vehicleTypeIds", path) or [],
    )
    if zone_type:
        rule_fields = {k: v for k, v in fields.items() if k in ZONE_RULE_FIELDS}
        for field, message in zone_problems(**rule_fields):
            reader.report.error(f"{path}.{ZONE_NAMES.get(field, field)}", message)
    return zone


ZONE_NAMES = {
    "vertices": "vertices",
    "max_speed": "maximumSpeed",
    "direction": "direction",
    "limitation": "directedLimitation",
    "penalty_factor": "penaltyFactor",
    "priority_factor": "priorityFactor",
    "release_loss_behavior": "releaseLossBehavior",
}


def _node(reader: Reader, raw: Any, path: str, layout: str) -> LifNode | None:
    data = reader.obj(raw, path)
    if data is None:
        return None
    reader.known(data, path, "node", NODE_KEYS)
    position = reader.obj(data.get("nodePosition"), f"{path}.nodePosition") or {}
    if position:
        reader.known(position, f"{path}.nodePosition", "nodePosition", ("x", "y"))
    where = f"{path}.nodePosition"
    node = LifNode(
        node_id=reader.string(data, "nodeId", path, required=True),
        x=reader.number(position, "x", where, required=bool(position)) or 0.0,
        y=reader.number(position, "y", where, required=bool(position)) or 0.0,
        map_id=reader.string(data, "mapId", path),
        layout=layout,
        path=path,
        name=reader.string(data, "nodeName", path),
        description=reader.string(data, "nodeDescription", path),
    )
    node.props = _vehicle_type_props(
        reader, data, path, "vehicleTypeNodeProperties", read_node_props
    )
    extension = _extension(reader, data, path, ("theta",))
    node.theta = reader.number(extension, "theta", f"{path}.{EXTENSION}")
    return node


def _edge(reader: Reader, raw: Any, path: str, layout: str) -> LifEdge | None:
    data = reader.obj(raw, path)
    if data is None:
        return None
    reader.known(data, path, "edge", EDGE_KEYS)
    edge = LifEdge(
        edge_id=reader.string(data, "edgeId", path, required=True),
        start=reader.string(data, "startNodeId", path, required=True),
        end=reader.string(data, "endNodeId", path, required=True),
        layout=layout,
        path=path,
        name=reader.string(data, "edgeName", path),
        description=reader.string(data, "edgeDescription", path),
    )
    edge.props = _vehicle_type_props(
        reader, data, path, "vehicleTypeEdgeProperties", read_edge_props
    )
    extension = _extension(reader, data, path, ("maxSpeed",))
    edge.max_speed = reader.number(extension, "maxSpeed", f"{path}.{EXTENSION}", positive=True)
    return edge


def _vehicle_type_props(
    reader: Reader,
    data: dict[str, Any],
    path: str,
    key: str,
    read: Callable[[Reader, Any, str], Props | None],
) -> list[Props]:
    """The vehicle-type properties of a node or edge, each read by `read`.

    The list is required; an empty one is allowed (the element is open to every vehicle).
    """
    items = reader.array(data, key, path, required=True)
    if items == []:
        reader.report.warn(f"{path}.{key}", "empty: open to every vehicle")
    props = (read(reader, item, f"{path}.{key}[{i}]") for i, item in enumerate(items or []))
    return [prop for prop in props if prop is not None]


def _station(reader: Reader, raw: Any, path: str, layout: str) -> LifStation | None:
    data = reader.obj(raw, path)
    if data is None:
        return None
    reader.known(data, path, "station", STATION_KEYS)
    node_ids = reader.strings(data, "interactionNodeIds", path)
    if node_ids is None and "interactionNodeIds" not in data:
        reader.report.error(f"{path}.interactionNodeIds", "missing required field")
    elif not node_ids:
        reader.report.error(f"{path}.interactionNodeIds", "needs at least one node")
    station = LifStation(
        station_id=reader.string(data, "stationId", path, required=True),
        node_ids=node_ids or [],
        layout=layout,
        path=path,
        name=reader.string(data, "stationName", path),
        description=reader.string(data, "stationDescription", path),
        height=reader.number(data, "stationHeight", path, minimum=0.0, lenient=True),
    )
    if "stationPosition" in data:
        where = f"{path}.stationPosition"
        position = reader.obj(data["stationPosition"], where) or {}
        reader.known(position, where, "stationPosition", ("x", "y", "theta"))
        x, y = (
            reader.number(position, "x", where, required=True),
            reader.number(position, "y", where, required=True),
        )
        if x is not None and y is not None:
            station.position = (x, y, reader.number(position, "theta", where))
    extension = _extension(reader, data, path, ("kind",))
    station.kind = reader.choice(extension, "kind", f"{path}.{EXTENSION}", Station.Kind.values)
    return station


def _extension(
    reader: Reader, data: dict[str, Any], path: str, keys: tuple[str, ...]
) -> dict[str, Any]:
    if EXTENSION not in data:
        return {}
    extension = reader.obj(data[EXTENSION], f"{path}.{EXTENSION}") or {}
    reader.known(extension, f"{path}.{EXTENSION}", EXTENSION, keys)
    return extension
