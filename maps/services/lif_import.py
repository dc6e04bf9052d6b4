"""Writes of LIF imports: a checked LIF file into maps, layouts, nodes, edges and stations."""

import math
from collections.abc import Mapping
from typing import Any

from django.db import transaction
from django.db.models import ProtectedError

from fleet import audit
from maps.lif import ids
from maps.lif.document import LifDocument, LifNode, LifStation
from maps.lif.parse import parse_lif
from maps.lif.report import ImportReport
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
    Zone,
)
from maps.services.zones import counter_clockwise

BATCH = 2000
ID_LENGTH = 100


class _Rollback(Exception):
    """Raised inside the transaction to undo every write when the report has errors."""


def import_lif(
    *,
    source: bytes | str | Mapping[str, Any],
    site_id: str = "default",
    replace: bool = False,
    file_name: str = "",
) -> ImportReport:
    """Import one LIF file into the site `site_id` (created if missing) and report on it.

    Each distinct node `mapId` becomes a map, each layout a `Layout`; vehicle types are created
    when new. Ids clashing with the site are prefixed (see `maps.lif.ids`). A project imported
    into the site before is refused unless `replace`, which deletes the earlier import's maps
    first (refused in turn while transport orders refer to their stations). When the report has
    errors, nothing was written.
    """
    document, report = parse_lif(source)
    report.site = site_id
    if document is None:
        return report
    try:
        with transaction.atomic():
            _write(document, report, site_id=site_id, replace=replace, file_name=file_name)
            if report.errors:
                raise _Rollback
            audit.record(
                "layout.import",
                target_type="site",
                target_id=site_id,
                detail={"file": file_name, "maps": report.maps, "replace": replace},
            )
    except _Rollback:
        report.maps, report.counts, report.import_pk = [], {}, None
    return report


def _write(
    document: LifDocument, report: ImportReport, *, site_id: str, replace: bool, file_name: str
) -> None:
    site, _ = Site.objects.get_or_create(site_id=site_id, defaults={"name": site_id})
    earlier = LifImport.objects.filter(site=site, project=document.project).first()
    if earlier is not None and not _replace(earlier, replace, report):
        return
    found = ids.clashes(site, ids.file_ids(document))
    if found:
        report.prefix = ids.prefix_for(document.project)
        report.warn(
            "$",
            f'ids clash with site "{site_id}" ({ids.describe(found)}): every id '
            f'of this file is prefixed with "{report.prefix}"',
        )
        ids.apply_prefix(document, report.prefix)
        still = ids.clashes(site, ids.file_ids(document))
        if still:
            report.error("$", f"ids clash even with the prefix: {ids.describe(still)}")
            return
    if not _lengths_fit(document, report):
        return
    lif_import = LifImport.objects.create(
        site=site,
        project=document.project,
        creator=document.creator,
        exported_at=document.export_timestamp,
        lif_version=document.lif_version,
        file_name=file_name[:255],
        prefix=report.prefix,
    )
    writer = _Writer(document, report, site, lif_import)
    writer.write()
    lif_import.report = report.as_dict()
    lif_import.save(update_fields=["report"])
    report.import_pk = lif_import.pk


def _replace(earlier: LifImport, replace: bool, report: ImportReport) -> bool:
    where = "$.metaInformation.projectIdentification"
    if not replace:
        report.error(
            where,
            f'project "{earlier.project}" is already imported into this site; '
            "import with replace to replace it",
        )
        return False
    maps = Map.objects.filter(lif_import=earlier)
    try:
        Station.objects.filter(map__in=maps).delete()
        maps.delete()
    except ProtectedError as exc:
        refs = sorted({str(obj) for obj in exc.protected_objects})[:3]
        report.error(
            where, f"cannot replace: other records refer to its stations ({', '.join(refs)})"
        )
        return False
    earlier.delete()
    return True


def _lengths_fit(document: LifDocument, report: ImportReport) -> bool:
    errors = len(report.errors)
    checks: list[tuple[str, str]] = [
        (la.path + ".layoutId", la.layout_id) for la in document.layouts
    ]
    checks += [(n.path + ".nodeId", n.node_id) for n in document.nodes()]
    checks += [(n.path + ".mapId", n.map_id) for n in document.nodes()]
    checks += [(e.path + ".edgeId", e.edge_id) for e in document.edges()]
    checks += [(s.path + ".stationId", s.station_id) for s in document.stations()]
    checks += [(z.path + ".zoneId", z.zone_id) for z in document.zones()]
    for path, value in checks:
        if len(value) > ID_LENGTH:
            report.error(path, f"id longer than {ID_LENGTH} characters")
    return len(report.errors) == errors


class _Writer:
    """Bulk-creates the rows of one checked document."""

    def __init__(
        self, document: LifDocument, report: ImportReport, site: Site, lif_import: LifImport
    ) -> None:
        self.document, self.report, self.site, self.lif_import = document, report, site, lif_import
        self.prefix = report.prefix

    def write(self) -> None:
        types = self._vehicle_types()
        layouts = self._layouts()
        maps = self._maps()
        nodes = self._nodes(maps, layouts)
        NodeProperty.objects.bulk_create(
            (
                NodeProperty(
                    node=nodes[n.node_id],
                    vehicle_type=types[p.vehicle_type],
                    theta=p.theta,
                    actions=p.actions,
                )
                for n in self.document.nodes()
                for p in n.props
            ),
            batch_size=BATCH,
        )
        edges = Edge.objects.bulk_create(
            (self._edge(e, nodes, layouts) for e in self.document.edges()), batch_size=BATCH
        )
        by_edge = dict(zip((e.edge_id for e in self.document.edges()), edges, strict=True))
        EdgeProperty.objects.bulk_create(
            (
                EdgeProperty(
                    edge=by_edge[e.edge_id], vehicle_type=types[p.vehicle_type], **_edge_fields(p)
                )
                for e in self.document.edges()
                for p in e.props
            ),
            batch_size=BATCH,
        )
        stations = self._stations(nodes, layouts)
        zones = self._zones(maps, types)
        self.report.maps = list(maps)
        self.report.counts = {
            "maps": len(maps),
            "layouts": len(layouts),
            "nodes": len(nodes),
            "edges": len(edges),
            "stations": stations,
            "vehicle types": len(types),
        }
        if zones:
            self.report.counts["zones"] = zones

    def _vehicle_types(self) -> dict[str, VehicleType]:
        wanted = self.document.vehicle_types()
        types = {t.type_id: t for t in VehicleType.objects.filter(type_id__in=wanted)}
        new = [VehicleType(type_id=t, name=t) for t in wanted if t not in types]
        for vehicle_type in VehicleType.objects.bulk_create(new):
            types[vehicle_type.type_id] = vehicle_type
        return types

    def _layouts(self) -> dict[str, Layout]:
        rows = Layout.objects.bulk_create(
            Layout(
                site=self.site,
                lif_import=self.lif_import,
                layout_id=la.layout_id,
                name=la.name,
                version=la.version,
                level_id=la.level_id,
                description=la.description,
                position=i,
            )
            for i, la in enumerate(self.document.layouts)
        )
        return {row.layout_id: row for row in rows}

    def _maps(self) -> dict[str, Map]:
        first: dict[str, Any] = {}
        for layout in self.document.layouts:
            for node in layout.nodes:
                first.setdefault(node.map_id, layout)
        rows = Map.objects.bulk_create(
            Map(
                site=self.site,
                map_id=map_id,
                name=layout.name or map_id,
                level=layout.level_id,
                lif_import=self.lif_import,
                source_id=self._source(map_id),
            )
            for map_id, layout in first.items()
        )
        return {row.map_id: row for row in rows}

    def _nodes(self, maps: dict[str, Map], layouts: dict[str, Layout]) -> dict[str, Node]:
        rows = Node.objects.bulk_create(
            (
                Node(
                    map=maps[n.map_id],
                    node_id=n.node_id,
                    x=n.x,
                    y=n.y,
                    theta=_theta(n),
                    name=n.name[:200],
                    description=n.description,
                    layout=layouts[n.layout],
                    source_id=self._source(n.node_id),
                )
                for n in self.document.nodes()
            ),
            batch_size=BATCH,
        )
        return {row.node_id: row for row in rows}

    def _edge(self, edge: Any, nodes: dict[str, Node], layouts: dict[str, Layout]) -> Edge:
        start, end = nodes[edge.start], nodes[edge.end]
        return Edge(
            map=start.map,
            edge_id=edge.edge_id,
            start=start,
            end=end,
            length=math.hypot(end.x - start.x, end.y - start.y),
            max_speed=edge.max_speed,
            name=edge.name[:200],
            description=edge.description,
            layout=layouts[edge.layout],
            source_id=self._source(edge.edge_id),
        )

    def _stations(self, nodes: dict[str, Node], layouts: dict[str, Layout]) -> int:
        lif_nodes = {n.node_id: n for n in self.document.nodes()}
        stations = Station.objects.bulk_create(
            Station(
                map=nodes[s.node_ids[0]].map,
                station_id=s.station_id,
                name=s.name[:200],
                kind=s.kind or _infer_kind(s, lif_nodes),
                node=nodes[s.node_ids[0]],
                description=s.description,
                height=s.height,
                position_x=s.position[0] if s.position else None,
                position_y=s.position[1] if s.position else None,
                position_theta=s.position[2] if s.position else None,
                layout=layouts[s.layout],
                source_id=self._source(s.station_id),
            )
            for s in self.document.stations()
        )
        StationNode.objects.bulk_create(
            StationNode(station=row, node=nodes[node_id], position=i)
            for row, s in zip(stations, self.document.stations(), strict=True)
            for i, node_id in enumerate(s.node_ids)
        )
        return len(stations)

    def _zones(self, maps: dict[str, Map], types: dict[str, VehicleType]) -> int:
        zones = self.document.zones()
        rows = Zone.objects.bulk_create(
            Zone(
                map=maps[z.map_id],
                zone_id=z.zone_id,
                **{**z.fields, "vertices": counter_clockwise(z.fields["vertices"])},
            )
            for z in zones
        )
        Zone.vehicle_types.through.objects.bulk_create(
            Zone.vehicle_types.through(zone_id=row.pk, vehicletype_id=types[t].pk)
            for row, z in zip(rows, zones, strict=True)
            for t in dict.fromkeys(z.vehicle_types)
        )
        return len(rows)

    def _source(self, value: str) -> str:
        return value.removeprefix(self.prefix) if self.prefix else ""


def _theta(node: LifNode) -> float | None:
    """The heading for every vehicle: the extension's, or the one all vehicle types agree on."""
    if node.theta is not None or not node.props:
        return node.theta
    thetas = {p.theta for p in node.props}
    return thetas.pop() if len(thetas) == 1 else None


def _infer_kind(station: LifStation, nodes: dict[str, LifNode]) -> str:
    """A station's kind from the actions offered at its nodes: charging, pick and/or drop."""
    actions = {
        a.get("actionType", "").lower()
        for node_id in station.node_ids
        for p in nodes[node_id].props
        for a in p.actions
    }
    if "startcharging" in actions:
        return Station.Kind.CHARGE
    if {"pick", "drop"} <= actions:
        return Station.Kind.HANDOVER
    if "pick" in actions:
        return Station.Kind.PICK
    if "drop" in actions:
        return Station.Kind.DROP
    return Station.Kind.OTHER


def _edge_fields(p: Any) -> dict[str, Any]:
    return {
        "vehicle_orientation": p.vehicle_orientation,
        "orientation_type": p.orientation_type,
        "rotation_allowed": p.rotation_allowed,
        "rotation_at_start": p.rotation_at_start,
        "rotation_at_end": p.rotation_at_end,
        "max_speed": p.max_speed,
        "max_rotation_speed": p.max_rotation_speed,
        "min_height": p.min_height,
        "max_height": p.max_height,
        "load_unloaded": p.load_unloaded,
        "load_loaded": p.load_loaded,
        "load_set_names": p.load_set_names,
        "actions": p.actions,
        "trajectory": p.trajectory,
        "reentry_allowed": p.reentry_allowed,
    }
