"""Shortest paths on a directed layout graph, with rustworkx doing the graph work."""

from collections.abc import Iterable
from dataclasses import dataclass

import rustworkx as rx


class NoRouteError(Exception):
    """No directed path exists between two nodes (or a node is not in the layout)."""


@dataclass(frozen=True)
class GraphEdge:
    """A directed, traversable edge of the layout with its length in metres."""

    edge_id: str
    start: str
    end: str
    length: float


class RoutingGraph:
    """The layout as a directed graph keyed by node id; edge weights are lengths in metres."""

    def __init__(self, node_ids: Iterable[str], edges: Iterable[GraphEdge]) -> None:
        self._graph: rx.PyDiGraph = rx.PyDiGraph()
        self._index: dict[str, int] = {}
        for node_id in node_ids:
            self._index[node_id] = self._graph.add_node(node_id)
        self._edges: dict[tuple[str, str], GraphEdge] = {}
        for edge in edges:
            known = self._edges.get((edge.start, edge.end))
            if known is not None and known.length <= edge.length:
                continue  # of parallel edges, routing only ever wants the shortest
            self._edges[(edge.start, edge.end)] = edge
        for edge in self._edges.values():
            self._graph.add_edge(self._index[edge.start], self._index[edge.end], edge.length)
        self._reversed = self._graph.copy()
        self._reversed.reverse()

    def __contains__(self, node_id: object) -> bool:
        return node_id in self._index

    def edge_between(self, start: str, end: str) -> GraphEdge:
        """The (shortest) edge from `start` to `end`."""
        try:
            return self._edges[(start, end)]
        except KeyError:
            raise NoRouteError(f"no edge from {start} to {end}") from None

    def shortest_path(self, start: str, goal: str) -> list[str]:
        """Node ids from `start` to `goal` inclusive; `[start]` when they are the same node."""
        self._require(start, goal)
        if start == goal:
            return [start]
        paths = rx.dijkstra_shortest_paths(
            self._graph, self._index[start], target=self._index[goal], weight_fn=float
        )
        if self._index[goal] not in paths:
            raise NoRouteError(f"no route from {start} to {goal}")
        return [self._graph[i] for i in paths[self._index[goal]]]

    def path_length(self, path: list[str]) -> float:
        """Length in metres of a path given as consecutive node ids."""
        return sum(self.edge_between(a, b).length for a, b in zip(path, path[1:], strict=False))

    def distances_to(self, goal: str) -> dict[str, float]:
        """Shortest distance from every node that can reach `goal` (goal itself at 0)."""
        self._require(goal)
        lengths = rx.dijkstra_shortest_path_lengths(self._reversed, self._index[goal], float)
        distances = {self._reversed[i]: length for i, length in lengths.items()}
        distances[goal] = 0.0
        return distances

    def _require(self, *node_ids: str) -> None:
        for node_id in node_ids:
            if node_id not in self._index:
                raise NoRouteError(f"unknown node {node_id}")
