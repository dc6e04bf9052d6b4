"""Routing on a directed layout graph, with rustworkx doing the graph work.

Two views of one layout:

- by distance (`shortest_path`, `distances_to`, `path_length`): metres, every vehicle, every edge
  (`distances_to` scales an edge by its `cost_factor`, 1 unless a penalty or priority zone says);
- by travel time for a vehicle profile (`route`, `route_from_table`, `routes`,
  `travel_times_to`): seconds = length / min(edge limit, type limit, vehicle speed) plus turning
  on the spot, on the edges and nodes the profile's vehicle type may use (`traffic.timegraph`).

A graph may span several maps (floors): an edge whose end node is on another map is a transition
(a lift, a ramp), and routes cross it like any edge. Graphs are immutable snapshots; distance tables
are cached inside them, so a changed layout means a new graph (maps.selectors keys its cache on the
layout revision).
"""

import threading
from collections import OrderedDict
from collections.abc import Iterable, Mapping

import rustworkx as rx

from traffic.costs import VehicleProfile
from traffic.elements import GraphEdge, GraphNode, NoRouteError, Route
from traffic.timegraph import TimeGraph

__all__ = ["GraphEdge", "GraphNode", "NoRouteError", "Route", "RoutingGraph", "VehicleProfile"]

DISTANCE_CACHE_SIZE = 256  # distance tables (metres) kept, one per goal node
PROFILE_CACHE_SIZE = 16  # travel-time graphs kept, one per vehicle profile
ANY_VEHICLE = VehicleProfile()


class RoutingGraph:
    """The layout as a directed graph keyed by node id; edge weights are lengths in metres."""

    def __init__(self, nodes: Iterable[str | GraphNode], edges: Iterable[GraphEdge]) -> None:
        self._nodes: dict[str, GraphNode] = {}
        for node in nodes:
            graph_node = node if isinstance(node, GraphNode) else GraphNode(node)
            self._nodes[graph_node.node_id] = graph_node
        self._graph: rx.PyDiGraph = rx.PyDiGraph()
        self._index: dict[str, int] = {n: self._graph.add_node(n) for n in self._nodes}
        self._all_edges = [e for e in edges if e.start in self._index and e.end in self._index]
        self._edges: dict[tuple[str, str], GraphEdge] = {}
        for edge in self._all_edges:
            known = self._edges.get((edge.start, edge.end))
            if known is not None and _weight(known) <= _weight(edge):
                continue  # of parallel edges, routing by distance only ever wants the shortest
            self._edges[(edge.start, edge.end)] = edge
        for edge in self._edges.values():
            self._graph.add_edge(self._index[edge.start], self._index[edge.end], _weight(edge))
        self._reversed = self._graph.copy()
        self._reversed.reverse()
        self._distances: OrderedDict[str, dict[str, float]] = OrderedDict()
        self._profiles: OrderedDict[VehicleProfile, TimeGraph] = OrderedDict()
        self._lock = threading.Lock()

    def __contains__(self, node_id: object) -> bool:
        return node_id in self._index

    @property
    def nodes(self) -> Mapping[str, GraphNode]:
        """Every node by id."""
        return self._nodes

    @property
    def edges(self) -> list[GraphEdge]:
        """Every edge, parallel ones included."""
        return list(self._all_edges)

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
        """Shortest distance from every node that can reach `goal` (goal itself at 0); cached."""
        self._require(goal)
        with self._lock:
            cached = self._distances.get(goal)
            if cached is None:
                lengths = rx.dijkstra_shortest_path_lengths(
                    self._reversed, self._index[goal], float
                )
                cached = {self._reversed[i]: length for i, length in lengths.items()}
                cached[goal] = 0.0
                self._distances[goal] = cached
                if len(self._distances) > DISTANCE_CACHE_SIZE:
                    self._distances.popitem(last=False)
            else:
                self._distances.move_to_end(goal)
        return dict(cached)

    def route(self, start: str, goal: str, *, vehicle: VehicleProfile | None = None) -> Route:
        """The quickest route for `vehicle` (default: any vehicle at 1 m/s), fresh Dijkstra."""
        return self.for_vehicle(vehicle).route(start, goal)

    def route_from_table(
        self,
        start: str,
        goal: str,
        *,
        vehicle: VehicleProfile | None = None,
        start_heading: float | None = None,
    ) -> Route:
        """The quickest route read from the cached travel-time table to `goal`.

        The first call for a goal builds its table (one full Dijkstra); later calls for that goal
        from any start only walk the table. `start_heading` (rad) prices the first turn.
        """
        return self.for_vehicle(vehicle).route_from_table(start, goal, start_heading=start_heading)

    def routes(
        self,
        start: str,
        goal: str,
        k: int = 3,
        *,
        vehicle: VehicleProfile | None = None,
        max_stretch: float | None = 1.5,
        penalty: float = 1.0,
    ) -> list[Route]:
        """Up to `k` alternative routes, quickest first, none slower than `max_stretch` × best."""
        if k < 1:
            raise ValueError("k must be at least 1")
        return self.for_vehicle(vehicle).alternatives(
            start, goal, k, max_stretch=max_stretch, penalty=penalty
        )

    def travel_times_to(
        self, goal: str, *, vehicle: VehicleProfile | None = None
    ) -> dict[str, float]:
        """Seconds to `goal` from every node from which `vehicle` can reach it; cached."""
        return self.for_vehicle(vehicle).travel_times_to(goal)

    def for_vehicle(self, vehicle: VehicleProfile | None = None) -> TimeGraph:
        """The travel-time graph of a vehicle profile (built on first use, then cached)."""
        profile = vehicle or ANY_VEHICLE
        with self._lock:
            graph = self._profiles.get(profile)
            if graph is not None:
                self._profiles.move_to_end(profile)
                return graph
        graph = TimeGraph(self._nodes, self._all_edges, profile)
        with self._lock:
            graph = self._profiles.setdefault(profile, graph)
            if len(self._profiles) > PROFILE_CACHE_SIZE:
                self._profiles.popitem(last=False)
        return graph

    def _require(self, *node_ids: str) -> None:
        for node_id in node_ids:
            if node_id not in self._index:
                raise NoRouteError(f"unknown node {node_id}")


def _weight(edge: GraphEdge) -> float:
    """What routing by distance pays for an edge: its length, scaled by its zone cost factor."""
    return edge.length * edge.cost_factor
