"""Writes of layouts."""

import math
from typing import Any

from django.db import transaction

from fleet.exceptions import InvalidRequestError
from maps.models import Edge, Map, Node, Station


@transaction.atomic
def create_layout(*, spec: dict[str, Any], replace: bool = False) -> Map:
    """Create a map from plain layout data (`maps.demo.warehouse_layout` produces such data).

    `spec` holds `mapId`, `name`, `nodes` [{id, x, y, theta?}], `edges` [{id, start, end,
    maxSpeed?}] and `stations` [{id, name?, kind, node}]. Edge lengths are the straight-line
    distance between their nodes. With `replace`, an existing map of that id is deleted first;
    otherwise an existing id is an error.
    """
    existing = Map.objects.filter(map_id=spec["mapId"])
    if existing.exists():
        if not replace:
            raise InvalidRequestError(f"map {spec['mapId']} exists already")
        Station.objects.filter(map__in=existing).delete()
        existing.delete()
    layout = Map.objects.create(map_id=spec["mapId"], name=spec.get("name", spec["mapId"]))
    nodes = Node.objects.bulk_create(
        Node(map=layout, node_id=n["id"], x=n["x"], y=n["y"], theta=n.get("theta"))
        for n in spec["nodes"]
    )
    by_id = {node.node_id: node for node in nodes}
    Edge.objects.bulk_create(_edge(layout, by_id, e) for e in spec["edges"])
    Station.objects.bulk_create(
        Station(
            map=layout,
            station_id=s["id"],
            name=s.get("name", ""),
            kind=s["kind"],
            node=_node(by_id, s["node"]),
        )
        for s in spec.get("stations", [])
    )
    return layout


def _edge(layout: Map, by_id: dict[str, Node], spec: dict[str, Any]) -> Edge:
    start, end = _node(by_id, spec["start"]), _node(by_id, spec["end"])
    return Edge(
        map=layout,
        edge_id=spec["id"],
        start=start,
        end=end,
        length=math.hypot(end.x - start.x, end.y - start.y),
        max_speed=spec.get("maxSpeed"),
    )


def _node(by_id: dict[str, Node], node_id: str) -> Node:
    try:
        return by_id[node_id]
    except KeyError:
        raise InvalidRequestError(f"unknown node {node_id}") from None
