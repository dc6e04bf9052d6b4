"""Layout files exported by the fleet manager: nodes, edges and parking spots of one map.

The simulator only needs the layout for start positions and to know which ``mapId``
exists; vehicles drive along the coordinates carried by each order's ``nodePosition``.
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any


class LayoutError(ValueError):
    """Raised when a layout file is missing required data or is inconsistent."""


@dataclass(frozen=True, slots=True)
class LayoutNode:
    """One node of the layout with its world coordinates in metres."""

    node_id: str
    x: float
    y: float


@dataclass(frozen=True, slots=True)
class LayoutEdge:
    """One directed edge of the layout."""

    edge_id: str
    start: str
    end: str


@dataclass(frozen=True, slots=True)
class Layout:
    """A single-map layout: nodes by id, edges and the ordered parking node ids."""

    map_id: str
    nodes: dict[str, LayoutNode]
    edges: tuple[LayoutEdge, ...] = ()
    parking: tuple[str, ...] = field(default=())

    def start_node(self, index: int) -> LayoutNode:
        """Start node of vehicle ``index``: parking[i % len] or, without parking, nodes[i % len]."""
        if self.parking:
            return self.nodes[self.parking[index % len(self.parking)]]
        if not self.nodes:
            raise LayoutError("layout has no nodes to start on")
        ordered = list(self.nodes.values())
        return ordered[index % len(ordered)]

    def start_heading(self, node: LayoutNode) -> float:
        """Heading along the first edge leaving ``node`` so vehicles look somewhere sensible."""
        for edge in self.edges:
            if edge.start == node.node_id and edge.end in self.nodes:
                end = self.nodes[edge.end]
                return math.atan2(end.y - node.y, end.x - node.x)
        return 0.0

    @classmethod
    def from_dict(cls, data: dict[str, Any]) -> Layout:
        """Build a layout from the JSON structure the fleet manager exports."""
        try:
            map_id = str(data["mapId"])
            nodes = {
                str(raw["id"]): LayoutNode(str(raw["id"]), float(raw["x"]), float(raw["y"]))
                for raw in data.get("nodes", [])
            }
            edges = tuple(
                LayoutEdge(str(raw["id"]), str(raw["start"]), str(raw["end"]))
                for raw in data.get("edges", [])
            )
            parking = tuple(str(node_id) for node_id in data.get("parking") or [])
        except (KeyError, TypeError, ValueError) as exc:
            raise LayoutError(f"malformed layout: {exc!r}") from exc
        if not map_id:
            raise LayoutError("layout mapId must not be empty")
        if not nodes:
            raise LayoutError("layout has no nodes")
        unknown = [node_id for node_id in parking if node_id not in nodes]
        if unknown:
            raise LayoutError(f"parking refers to unknown nodes: {unknown}")
        return cls(map_id=map_id, nodes=nodes, edges=edges, parking=parking)


def load_layout(path: str | Path) -> Layout:
    """Read and parse a layout JSON file."""
    try:
        data = json.loads(Path(path).read_text(encoding="utf-8"))
    except (OSError, json.JSONDecodeError) as exc:
        raise LayoutError(f"cannot read layout {path}: {exc}") from exc
    if not isinstance(data, dict):
        raise LayoutError("layout root must be a JSON object")
    return Layout.from_dict(data)
