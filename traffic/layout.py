"""The layout as indexed arrays: what traffic planning works on.

Nodes are numbered 0..N-1 and directed edges 0..E-1. The two directions of a lane share one
*segment* (the floor area the lane covers), so reservations work on **resources**: node `i` is
resource `i` and segment `s` is resource `N + s`. Footprint conflict sets (`traffic.footprint`)
relate resources to each other; the planner never looks at geometry.

Build a layout from node and edge lists, from a `RoutingGraph` (the layout `maps` keeps), or
from a grid of free cells (benchmarks, tests).
"""

from __future__ import annotations

import math
from collections.abc import Collection, Iterable, Sequence
from dataclasses import dataclass

from traffic.routing import RoutingGraph


@dataclass(frozen=True)
class LayoutEdge:
    """A directed edge as the planner sees it: end nodes, metres, speed limit, shared segment."""

    start: int
    end: int
    length: float
    max_speed: float | None
    segment: int
    heading: float  # direction of travel (rad), from the node positions


class Layout:
    """Nodes with positions, directed edges and segments, all numbered; parking nodes marked.

    `parking` nodes are where idle vehicles wait: they must lie off the through paths (a vehicle
    parked there must not block travel between other nodes) for planning to stay complete.
    """

    def __init__(
        self,
        nodes: Sequence[tuple[str, float, float]],
        edges: Iterable[tuple[str, str, float | None, float | None]],
        *,
        parking: Collection[str] = (),
    ) -> None:
        self.node_ids: tuple[str, ...] = tuple(n for n, _, _ in nodes)
        self.index: dict[str, int] = {n: i for i, n in enumerate(self.node_ids)}
        if len(self.index) != len(self.node_ids):
            raise ValueError("node ids must be unique")
        self.xy: tuple[tuple[float, float], ...] = tuple((x, y) for _, x, y in nodes)
        self.edges: list[LayoutEdge] = []
        self.out: list[list[int]] = [[] for _ in self.node_ids]
        self.segment_ends: list[tuple[int, int]] = []
        segments: dict[tuple[int, int], int] = {}
        seen: set[tuple[int, int]] = set()
        for start_id, end_id, length, max_speed in edges:
            a, b = self.index[start_id], self.index[end_id]
            if a == b or (a, b) in seen:
                continue  # no loops; of parallel edges the first wins
            seen.add((a, b))
            key = (min(a, b), max(a, b))
            segment = segments.get(key)
            if segment is None:
                segment = segments[key] = len(self.segment_ends)
                self.segment_ends.append(key)
            (xa, ya), (xb, yb) = self.xy[a], self.xy[b]
            dx, dy = xb - xa, yb - ya
            metres = length if length is not None else math.hypot(dx, dy)
            if metres <= 0:
                raise ValueError(f"edge {start_id}->{end_id} has no length")
            self.out[a].append(len(self.edges))
            self.edges.append(
                LayoutEdge(a, b, metres, max_speed, segment, math.atan2(dy, dx) if metres else 0.0)
            )
        unknown = set(parking) - self.index.keys()
        if unknown:
            raise ValueError(f"unknown parking nodes {sorted(unknown)}")
        self.parking: frozenset[int] = frozenset(self.index[p] for p in parking)

    @property
    def node_count(self) -> int:
        """Number of nodes (node resources are 0..node_count-1)."""
        return len(self.node_ids)

    @property
    def resource_count(self) -> int:
        """Nodes plus segments."""
        return len(self.node_ids) + len(self.segment_ends)

    def segment_resource(self, edge: int) -> int:
        """The resource of the segment a directed edge drives on."""
        return len(self.node_ids) + self.edges[edge].segment

    def node(self, node_id: str) -> int:
        """The index of a node id (KeyError for an unknown node)."""
        return self.index[node_id]

    @classmethod
    def from_routing_graph(cls, graph: RoutingGraph, *, parking: Collection[str] = ()) -> Layout:
        """The layout of a `RoutingGraph` (positions in metres, edge lengths and speed limits)."""
        nodes = [(n.node_id, n.x, n.y) for n in graph.nodes.values()]
        edges = [(e.start, e.end, e.length, e.max_speed) for e in graph.edges]
        return cls(nodes, edges, parking=parking)

    @classmethod
    def grid(
        cls,
        free: Iterable[tuple[int, int]],
        *,
        pitch: float = 1.0,
        parking: Collection[tuple[int, int]] = (),
        one_way: dict[tuple[int, int], Collection[tuple[int, int]]] | None = None,
    ) -> Layout:
        """A 4-connected grid of free (row, col) cells, `pitch` metres apart, node ids "r,c".

        Row 0 is the top row (y = 0, rows grow towards -y), column 0 the left one. Every pair of
        free neighbours gets edges both ways unless `one_way` maps a cell to the only
        (drow, dcol) directions allowed out of it.
        """
        cells = sorted(set(free))
        present = set(cells)
        nodes = [(f"{r},{c}", c * pitch, -r * pitch) for r, c in cells]
        edges: list[tuple[str, str, float | None, float | None]] = []
        for r, c in cells:
            allowed = None if one_way is None else one_way.get((r, c))
            for dr, dc in ((0, 1), (1, 0), (0, -1), (-1, 0)):
                if (r + dr, c + dc) in present and (allowed is None or (dr, dc) in allowed):
                    edges.append((f"{r},{c}", f"{r + dr},{c + dc}", pitch, None))
        return cls(nodes, edges, parking=[f"{r},{c}" for r, c in parking])
