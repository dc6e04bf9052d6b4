"""Checks across a LIF file: unique ids, references between nodes, edges and stations, maps."""

from collections import Counter
from collections.abc import Iterable

from maps.lif.document import LifDocument, LifLayout, LifNode
from maps.lif.report import ImportReport


def check_references(document: LifDocument, report: ImportReport) -> None:
    """Note duplicate ids and references to unknown nodes; give nodes without mapId a map."""
    _unique(report, ((la.layout_id, la.path, "layoutId") for la in document.layouts), "layout")
    _unique(report, ((n.node_id, n.path, "nodeId") for n in document.nodes()), "node")
    _unique(report, ((e.edge_id, e.path, "edgeId") for e in document.edges()), "edge")
    _unique(report, ((s.station_id, s.path, "stationId") for s in document.stations()), "station")
    nodes = {n.node_id: n for n in document.nodes()}
    for edge in document.edges():
        for key, node_id in (("startNodeId", edge.start), ("endNodeId", edge.end)):
            if node_id and node_id not in nodes:
                report.error(f"{edge.path}.{key}", f'unknown node "{node_id}"')
        start = nodes.get(edge.start)
        if start is not None and start.layout != edge.layout:
            report.warn(
                f"{edge.path}.startNodeId",
                f'node "{edge.start}" is in layout "{start.layout}", not in this one',
            )
    for station in document.stations():
        seen: set[str] = set()
        for i, node_id in enumerate(station.node_ids):
            where = f"{station.path}.interactionNodeIds[{i}]"
            if node_id not in nodes:
                report.error(where, f'unknown node "{node_id}"')
            elif node_id in seen:
                report.warn(where, f'node "{node_id}" listed twice; kept once')
            seen.add(node_id)
        station.node_ids = list(dict.fromkeys(station.node_ids))
    for node in document.nodes():
        _one_per_type(report, node.path, "vehicleTypeNodeProperties", node.props)
    for edge in document.edges():
        _one_per_type(report, edge.path, "vehicleTypeEdgeProperties", edge.props)
    for layout in document.layouts:
        _place_on_maps(layout, report)
    _levels(document, report)
    _zones(document, report)


def _unique(report: ImportReport, items: Iterable[tuple[str, str, str]], what: str) -> None:
    first: dict[str, str] = {}
    for value, path, key in items:
        if not value:
            continue
        if value in first:
            report.error(f"{path}.{key}", f'duplicate {what} id "{value}" (also at {first[value]})')
        else:
            first[value] = path


def _one_per_type(report: ImportReport, path: str, key: str, props: Iterable[object]) -> None:
    seen: set[str] = set()
    for i, prop in enumerate(props):
        vehicle_type = str(getattr(prop, "vehicle_type", ""))
        if vehicle_type in seen:
            report.error(
                f"{path}.{key}[{i}].vehicleTypeId",
                f'second property for vehicle type "{vehicle_type}" (LIF allows one per type)',
            )
        seen.add(vehicle_type)


def _place_on_maps(layout: LifLayout, report: ImportReport) -> None:
    """Nodes without mapId go on the layout's most used map, else on a map named after it."""
    missing: list[LifNode] = [n for n in layout.nodes if not n.map_id]
    if not missing:
        return
    used = Counter(n.map_id for n in layout.nodes if n.map_id)
    map_id = used.most_common(1)[0][0] if used else layout.layout_id
    for node in missing:
        node.map_id = map_id
    report.warn(
        f"{missing[0].path}.mapId",
        f'{len(missing)} node(s) of layout "{layout.layout_id}" have no mapId; '
        f'put on map "{map_id}"',
    )


def _levels(document: LifDocument, report: ImportReport) -> None:
    level_of: dict[str, tuple[str, str]] = {}
    for layout in document.layouts:
        for map_id in dict.fromkeys(n.map_id for n in layout.nodes):
            known = level_of.setdefault(map_id, (layout.level_id, layout.layout_id))
            if known[0] != layout.level_id:
                report.warn(
                    f"{layout.path}.layoutLevelId",
                    f'map "{map_id}" is on level "{known[0]}" in layout "{known[1]}" '
                    f'and on "{layout.level_id}" here; the first is kept',
                )


def _zones(document: LifDocument, report: ImportReport) -> None:
    """Zones lie on a map of the file, with ids unique per map."""
    maps = {n.map_id for n in document.nodes()}
    _unique(
        report,
        ((f"{z.map_id}/{z.zone_id}", z.path, "zoneId") for z in document.zones()),
        "zone",
    )
    for zone in document.zones():
        if zone.map_id and zone.map_id not in maps:
            report.error(f"{zone.path}.mapId", f'no node of the file is on map "{zone.map_id}"')
