"""Writes of layouts from plain data, and the revision bump routing caches key on."""

import math
from collections.abc import Iterable
from typing import Any

from django.db import transaction
from django.db.models import F
from django.utils import timezone

from fleet.exceptions import InvalidRequestError
from maps.models import Edge, Map, Node, Site, Station, StationNode


@transaction.atomic
def create_layout(*, spec: dict[str, Any], replace: bool = False) -> Map:
    """Create a map from plain layout data (`maps.demo.warehouse_layout` produces such data).

    `spec` holds `mapId`, `name`, `nodes` [{id, x, y, theta?}], `edges` [{id, start, end,
    maxSpeed?}] and `stations` [{id, name?, kind, node}], optionally `site` (a site id, created
    if missing) and `level`. Edge lengths are the straight-line distance between their nodes. With
    `replace`, an existing map of that id is deleted first; otherwise an existing id is an error.
    """
    existing = Map.objects.filter(map_id=spec["mapId"])
    if existing.exists():
        if not replace:
            raise InvalidRequestError(f"map {spec['mapId']} exists already")
        Station.objects.filter(map__in=existing).delete()
        existing.delete()
    site = None
    if spec.get("site"):
        site, _ = Site.objects.get_or_create(site_id=spec["site"], defaults={"name": spec["site"]})
    layout = Map.objects.create(
        map_id=spec["mapId"],
        name=spec.get("name", spec["mapId"]),
        site=site,
        level=spec.get("level", ""),
    )
    nodes = Node.objects.bulk_create(
        Node(map=layout, node_id=n["id"], x=n["x"], y=n["y"], theta=n.get("theta"))
        for n in spec["nodes"]
    )
    by_id = {node.node_id: node for node in nodes}
    Edge.objects.bulk_create(_edge(layout, by_id, e) for e in spec["edges"])
    stations = Station.objects.bulk_create(
        Station(
            map=layout,
            station_id=s["id"],
            name=s.get("name", ""),
            kind=s["kind"],
            node=_node(by_id, s["node"]),
        )
        for s in spec.get("stations", [])
    )
    StationNode.objects.bulk_create(StationNode(station=s, node=s.node) for s in stations)
    return layout


def mark_layout_changed(*, maps: Iterable[Map]) -> None:
    """Record that the graph or stations of `maps` changed, so routing caches drop them.

    Every write of nodes, edges, properties or stations outside the services here (the admin,
    later the editor) must call this.
    """
    pks = [m.pk for m in maps if m.pk is not None]
    Map.objects.filter(pk__in=pks).update(revision=F("revision") + 1, updated_at=timezone.now())


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
