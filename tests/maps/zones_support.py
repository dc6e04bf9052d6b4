"""Helpers for the zone tests: rectangles as zone vertices, points of a route."""

from typing import Any

from maps.models import Map, Node


def box(x1: float, y1: float, x2: float, y2: float) -> list[dict[str, float]]:
    """The rectangle between two corners as zone vertices."""
    return [{"x": x1, "y": y1}, {"x": x2, "y": y1}, {"x": x2, "y": y2}, {"x": x1, "y": y2}]


def positions(layout: Map, node_ids: list[str]) -> list[tuple[float, float]]:
    nodes = {n.node_id: (n.x, n.y) for n in Node.objects.filter(map=layout)}
    return [nodes[n] for n in node_ids]


def zone_fields(**fields: Any) -> dict[str, Any]:
    return {"zone_id": "Z1", "zone_type": "BLOCKED", **fields}
