"""Reads of layouts: the routing graph and the layout as plain data for pages and the simulator."""

from typing import Any

from maps.models import Edge, Map, Node, Station
from traffic import RoutingGraph
from traffic.routing import GraphEdge


def load_graph(*, map: Map) -> RoutingGraph:
    """The routing graph of `map` (node ids as keys, edge lengths as weights)."""
    node_ids = list(Node.objects.filter(map=map).values_list("node_id", flat=True))
    edges = [
        GraphEdge(edge_id=edge_id, start=start, end=end, length=length)
        for edge_id, start, end, length in Edge.objects.filter(map=map).values_list(
            "edge_id", "start__node_id", "end__node_id", "length"
        )
    ]
    return RoutingGraph(node_ids, edges)


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
    return {
        "mapId": map.map_id,
        "name": map.name,
        "nodes": nodes,
        "edges": edges,
        "stations": stations,
        "parking": parking,
    }
