"""Id clashes between LIF files of one site, and the prefix that resolves them.

The rule: LIF ids are unique within one file, not across the files of several integrators. When
any map, layout, node, edge or station id of an incoming file is already used in the site (map
ids: anywhere, they are global), every one of those ids in the file gets the prefix
"<slug of projectIdentification>:" (e.g. "lif-example-02:N1"), with a warning naming the clashes.
Vehicle type ids are never prefixed: the same id means the same kind of vehicle. The file's own
ids are kept as `source_id` on each row, for translating what vehicles of that integrator report.
"""

from django.utils.text import slugify

from maps.lif.document import LifDocument
from maps.models import Edge, Layout, Map, Node, Site, Station

SEPARATOR = ":"


def file_ids(document: LifDocument) -> dict[str, set[str]]:
    """Every id of the file by kind."""
    return {
        "map": {n.map_id for n in document.nodes()},
        "layout": {la.layout_id for la in document.layouts},
        "node": {n.node_id for n in document.nodes()},
        "edge": {e.edge_id for e in document.edges()},
        "station": {s.station_id for s in document.stations()},
    }


def clashes(site: Site, ids: dict[str, set[str]]) -> dict[str, list[str]]:
    """The ids of `ids` already taken, by kind (sorted; kinds without clashes left out)."""
    taken = {
        "map": Map.objects.filter(map_id__in=ids["map"]).values_list("map_id", flat=True),
        "layout": Layout.objects.filter(site=site, layout_id__in=ids["layout"]).values_list(
            "layout_id", flat=True
        ),
        "node": Node.objects.filter(map__site=site, node_id__in=ids["node"]).values_list(
            "node_id", flat=True
        ),
        "edge": Edge.objects.filter(map__site=site, edge_id__in=ids["edge"]).values_list(
            "edge_id", flat=True
        ),
        "station": Station.objects.filter(
            map__site=site, station_id__in=ids["station"]
        ).values_list("station_id", flat=True),
    }
    return {kind: sorted(set(found)) for kind, found in taken.items() if found}


def prefix_for(project: str) -> str:
    """The prefix for a file's ids: its project, slugified."""
    return (slugify(project) or "lif") + SEPARATOR


def describe(found: dict[str, list[str]], limit: int = 3) -> str:
    """'nodes N1, N2; maps M1' for a warning."""
    parts = []
    for kind, values in found.items():
        more = f" and {len(values) - limit} more" if len(values) > limit else ""
        parts.append(f"{kind}s {', '.join(values[:limit])}{more}")
    return "; ".join(parts)


def apply_prefix(document: LifDocument, prefix: str) -> None:
    """Put `prefix` before every map, layout, node, edge and station id of the file."""
    for layout in document.layouts:
        layout.layout_id = prefix + layout.layout_id
        for node in layout.nodes:
            node.node_id, node.map_id = prefix + node.node_id, prefix + node.map_id
            node.layout = layout.layout_id
        for edge in layout.edges:
            edge.edge_id, edge.layout = prefix + edge.edge_id, layout.layout_id
            edge.start, edge.end = prefix + edge.start, prefix + edge.end
        for station in layout.stations:
            station.station_id, station.layout = prefix + station.station_id, layout.layout_id
            station.node_ids = [prefix + n for n in station.node_ids]
        for zone in layout.zones:
            zone.map_id = prefix + zone.map_id
