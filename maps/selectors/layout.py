"""Reads of layouts as plain data: for pages, the simulator and LIF export."""

from typing import Any

from maps.lif.export import export_lif
from maps.models import Edge, Map, Node, Site, Station, Zone


def get_default_map() -> Map | None:
    """The first map, used by pages and commands when no map is named."""
    return Map.objects.order_by("pk").first()


def layout_as_dict(*, map: Map) -> dict[str, Any]:
    """The layout as plain data: for the live page and for the simulator's `--layout` file."""
    nodes = [
        {"id": n.node_id, "x": n.x, "y": n.y, "theta": n.theta}
        for n in Node.objects.filter(map=map).order_by("node_id")
    ]
    edges = [
        {"id": e.edge_id, "start": e.start.node_id, "end": e.end.node_id, "length": e.length}
        for e in Edge.objects.filter(map=map).select_related("start", "end").order_by("edge_id")
    ]
    stations = [
        {
            "id": s.station_id,
            "name": s.name or s.station_id,
            "kind": s.kind,
            "node": s.node.node_id,
            "x": s.node.x,
            "y": s.node.y,
        }
        for s in Station.objects.filter(map=map).select_related("node").order_by("station_id")
    ]
    parking = [s["node"] for s in stations if s["kind"] == Station.Kind.PARK]
    zones = [
        {
            "id": z.zone_id,
            "name": z.name or z.zone_id,
            "type": z.zone_type,
            "vertices": [[v["x"], v["y"]] for v in z.vertices],
            "maxSpeed": z.max_speed,
        }
        for z in Zone.objects.filter(map=map, enabled=True).order_by("zone_id")
    ]
    return {
        "mapId": map.map_id,
        "name": map.name,
        "nodes": nodes,
        "edges": edges,
        "stations": stations,
        "parking": parking,
        "zones": zones,
    }


def export_map_lif(*, map: Map) -> dict[str, Any]:
    """One map as a LIF 1.0 document (edges to other floors left out)."""
    return export_lif(maps=[map])


def export_site_lif(*, site: Site) -> dict[str, Any]:
    """Every map of a site as one LIF 1.0 document, transitions between floors included."""
    return export_lif(maps=list(Map.objects.filter(site=site).select_related("lif_import", "site")))
