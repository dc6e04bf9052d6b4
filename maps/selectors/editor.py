"""Reads for the layout editor: a map as the editor's data, and the maps to choose from."""

from collections import defaultdict
from typing import Any

from django.db.models import Count, F, OuterRef, Q, QuerySet, Subquery
from django.db.models.functions import Coalesce
from django.urls import reverse

from maps.models import Edge, Map, Node, Station, StationNode, VehicleType, Zone
from maps.selectors.zones import list_zones, zone_as_dict


def list_editable_maps() -> QuerySet[Map]:
    """Every map with its node, edge, station and zone counts, by site and id."""
    return (
        Map.objects.select_related("site")
        .annotate(
            node_count=_count(Node),
            edge_count=_count(Edge),
            station_count=_count(Station),
            zone_count=_count(Zone),
        )
        .order_by(F("site__site_id").asc(nulls_first=True), "map_id")
    )


def _count(model: type[Node | Edge | Station | Zone]) -> Coalesce:
    """Rows of `model` per map, as a subquery (joining all four would multiply the rows)."""
    rows = model.objects.filter(map=OuterRef("pk")).order_by().values("map")
    return Coalesce(Subquery(rows.annotate(n=Count("pk")).values("n")[:1]), 0)


def editor_data(*, map: Map) -> dict[str, Any]:
    """Everything the editor page starts from (the payload it saves has the same shape).

    Edges are those with both ends on this map; transitions to other floors are kept as they are
    by a save and only counted here. `takenIds` are ids other maps of the site use, so the editor
    can name new elements without clashes.
    """
    rows = (
        Node.objects.filter(map=map)
        .order_by("pk")
        .values_list("pk", "node_id", "x", "y", "theta", "name")
    )
    ids = {pk: node_id for pk, node_id, *_ in rows}
    nodes = [
        {"id": node_id, "x": x, "y": y, "theta": theta, "name": name}
        for _, node_id, x, y, theta, name in rows
    ]
    edges = [  # joins cost more than looking the node ids up here
        {"id": edge_id, "start": ids[start], "end": ids[end], "maxSpeed": max_speed, "name": name}
        for edge_id, start, end, max_speed, name in Edge.objects.filter(map=map)
        .order_by("pk")
        .values_list("edge_id", "start_id", "end_id", "max_speed", "name")
        if end in ids and start in ids
    ]
    return {
        "map": _map_info(map),
        "nodes": nodes,
        "edges": edges,
        "stations": _stations(map),
        "zones": [zone_as_dict(z) for z in list_zones(map=map)],
        "transitions": Edge.objects.filter(Q(map=map) | Q(end__map=map))
        .exclude(start__map=F("end__map"))
        .count(),
        "choices": {
            "stationKinds": Station.Kind.choices,
            "zoneTypes": Zone.Type.choices,
            "limitations": Zone.Limitation.choices,
            "releaseLoss": Zone.ReleaseLoss.choices,
            "vehicleTypes": list(VehicleType.objects.values_list("type_id", flat=True)),
        },
        "takenIds": _taken_ids(map),
        "urls": {
            "save": reverse("maps:save", args=[map.pk]),
            "check": reverse("maps:check", args=[map.pk]),
            "list": reverse("maps:list"),
            "admin": reverse("admin:maps_map_change", args=[map.pk]),
        },
    }


def _map_info(map: Map) -> dict[str, Any]:
    floor_plan = None
    if map.floor_plan:
        floor_plan = reverse("maps:floor-plan", args=[map.pk])
    return {
        "pk": map.pk,
        "mapId": map.map_id,
        "name": map.name,
        "site": map.site.site_id if map.site else None,
        "level": map.level,
        "revision": map.revision,
        "version": map.version,
        "floorPlan": {
            "url": floor_plan,
            "scale": map.floor_plan_scale,
            "originX": map.floor_plan_origin_x,
            "originY": map.floor_plan_origin_y,
            "rotation": map.floor_plan_rotation,
        },
    }


def _stations(map: Map) -> list[dict[str, Any]]:
    interaction: dict[int, list[str]] = defaultdict(list)
    for station_pk, node_id in (
        StationNode.objects.filter(station__map=map)
        .order_by("station", "position")
        .values_list("station_id", "node__node_id")
    ):
        interaction[station_pk].append(node_id)
    return [
        {"id": station_id, "name": name, "kind": kind, "nodes": interaction.get(pk) or [node]}
        for pk, station_id, name, kind, node in Station.objects.filter(map=map)
        .order_by("station_id")
        .values_list("pk", "station_id", "name", "kind", "node__node_id")
    ]


def _taken_ids(map: Map) -> dict[str, list[str]]:
    """Ids the editor must not give new elements: the site's other maps use them, or this map's
    transitions to other floors (which a save keeps)."""
    transitions = transition_edge_ids(map)
    if map.site_id is None:
        return {"nodes": [], "edges": transitions, "stations": []}
    others = Map.objects.filter(site_id=map.site_id).exclude(pk=map.pk)
    return {
        "nodes": list(Node.objects.filter(map__in=others).values_list("node_id", flat=True)),
        "edges": transitions
        + list(Edge.objects.filter(map__in=others).values_list("edge_id", flat=True)),
        "stations": list(
            Station.objects.filter(map__in=others).values_list("station_id", flat=True)
        ),
    }


def transition_edge_ids(map: Map) -> list[str]:
    """Ids of the edges of `map` that end on another floor."""
    own = set(Node.objects.filter(map=map).values_list("pk", flat=True))
    return [
        edge_id
        for edge_id, end in Edge.objects.filter(map=map).order_by().values_list("edge_id", "end_id")
        if end not in own
    ]
