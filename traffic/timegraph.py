"""Travel-time routing for one vehicle profile on an edge-expanded graph (rustworkx does the
searches, scipy the distance tables).

A vehicle's cost at a node depends on the heading it arrives with, so the states are not the nodes
but the usable edges: the state of edge e is "has just driven e, stands at e's end node with the
heading e gave it". Per node there is also a departure state (the route starts here, heading free)
and an arrival state (the route ends here, after turning to the node's theta if it has one).
Transitions cost turning on the spot at the shared node plus driving the next edge; a turn the
rules forbid has no transition. Transition payloads are indices into a weight list, so the
k-alternatives search can penalise transitions without rebuilding the graph.

A distance table (seconds to one goal from every state) is a reverse Dijkstra over the whole
graph. rustworkx called back into Python for every transition's weight: 17–35 ms a table on the
load benchmark's layout (14,190 states, 53,590 transitions), and the API's step check, dispatch's
pricing and its routing each build up to three tables for an order with new stops. scipy's
csgraph runs it on a sparse matrix of the reversed transitions without callbacks: 3–6 ms, the
same distances (docs/LOAD.md, eleventh round).
"""

from __future__ import annotations

import math
import threading
from array import array
from collections import OrderedDict
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass

import numpy as np
import rustworkx as rx
from scipy.sparse import csr_array
from scipy.sparse.csgraph import dijkstra

from traffic.costs import EdgeRule, VehicleProfile, turn_angle, turn_directions, turn_via
from traffic.elements import GraphEdge, GraphNode, NoRouteError, Route
from traffic.geometry import heading

TABLE_CACHE_SIZE = 128  # distance tables kept per profile (one per goal node)


@dataclass(frozen=True)
class _Leg:
    """A usable edge as the profile drives it."""

    state: int
    edge: GraphEdge
    rule: EdgeRule
    length: float
    time: float
    heading_start: float | None
    heading_end: float | None


class TimeGraph:
    """The layout as one vehicle profile sees it: usable edges weighted by travel time (s)."""

    def __init__(
        self, nodes: Mapping[str, GraphNode], edges: Iterable[GraphEdge], profile: VehicleProfile
    ) -> None:
        self.profile = profile
        self._nodes = nodes
        self._graph: rx.PyDiGraph = rx.PyDiGraph()
        self._weights: list[float] = []
        self._into: dict[int, list[int]] = {}  # state -> transitions entering it
        usable = [n for n in nodes.values() if n.usable_by(profile)]
        self._depart = {n.node_id: self._graph.add_node(None) for n in usable}
        self._arrive = {n.node_id: self._graph.add_node(None) for n in usable}
        self._legs: dict[int, _Leg] = {}
        for edge in edges:
            leg = self._leg(edge)
            if leg is not None:
                self._legs[leg.state] = leg
        self._connect()
        self._reversed: csr_array | None = None
        self._tables: OrderedDict[str, array[float]] = OrderedDict()
        self._lock = threading.Lock()

    def route(self, start: str, goal: str) -> Route:
        """The quickest route from `start` to `goal` (fresh Dijkstra, stops at the goal)."""
        self._require(start, goal)
        if start == goal:
            return self._route_of([], start)
        return self._search(start, goal, self._weights)

    def route_from_table(
        self, start: str, goal: str, *, start_heading: float | None = None
    ) -> Route:
        """The quickest route, read from the cached distance table to `goal` (built if missing).

        With `start_heading` the vehicle stands at `start` with that heading and pays for (or may
        be forbidden) the turn onto the first edge.
        """
        self._require(start, goal)
        if start == goal:
            return self._route_of([], start)
        table = self._table(goal)
        source = self._depart[start]
        first: list[int] = []
        extra = 0.0
        if start_heading is not None:
            options = []
            for leg in self._legs_from(start):
                directions = turn_directions(leg.rule.rotation_at_start)
                angle = turn_angle(start_heading, leg.heading_start, directions)
                if angle is not None:
                    cost = self._turn_time(angle, leg) + leg.time + table[leg.state]
                    options.append((cost, leg.state))
            if not options or math.isinf(min(options)[0]):
                raise NoRouteError(f"no route from {start} to {goal} with that heading")
            best_cost, best_state = min(options)
            first = [best_state]
            extra = best_cost - self._legs[best_state].time - table[best_state]
        elif math.isinf(table[source]):
            raise NoRouteError(f"no route from {start} to {goal} for {self._who()}")
        path = self._descend([source, *first], table, self._arrive[goal])
        if path is None:  # a zero-cost detour fooled the greedy walk: search afresh
            return self.route(start, goal)
        return self._route_of(path, start, extra=extra)

    def travel_times_to(self, goal: str) -> dict[str, float]:
        """Seconds to `goal` from every node that can reach it (cached per goal)."""
        self._require(goal)
        table = self._table(goal)
        times = {n: table[s] for n, s in self._depart.items() if not math.isinf(table[s])}
        times[goal] = 0.0
        return times

    def alternatives(
        self, start: str, goal: str, k: int, *, max_stretch: float | None, penalty: float
    ) -> list[Route]:
        """Up to `k` different routes, quickest first, each within `max_stretch` × the best.

        Penalty method: after each route, the edges it drives cost (1 + penalty) times more and
        Dijkstra runs again, so later routes avoid earlier ones where a detour is affordable.
        """
        best = last = self.route(start, goal)
        routes, weights = [best], list(self._weights)
        limit = best.travel_time * max_stretch if max_stretch is not None else math.inf
        for _ in range(3 * k):
            if len(routes) >= k or not best.edges:
                break
            self._penalise(last, weights, penalty)
            last = self._search(start, goal, weights)
            if last.travel_time > limit + 1e-9:
                break
            if all(last.edges != r.edges for r in routes):
                routes.append(last)
        return sorted(routes, key=lambda r: (r.travel_time, r.length))

    def _leg(self, edge: GraphEdge) -> _Leg | None:
        if edge.start not in self._depart or edge.end not in self._depart:
            return None
        rule = edge.rule_for(self.profile)
        if rule is None:
            return None
        start, end = self._nodes[edge.start], self._nodes[edge.end]
        if rule.trajectory is not None:
            curve = rule.trajectory
            length = curve.length()
            travel_start, travel_end = curve.start_heading(), curve.end_heading()
        else:
            length = edge.length
            travel_start = travel_end = heading(end.x - start.x, end.y - start.y)
        speeds = [s for s in (self.profile.max_speed, edge.max_speed, rule.max_speed) if s]
        time = (length / min(speeds) if speeds else length) * edge.cost_factor
        return _Leg(
            state=self._graph.add_node(edge.edge_id),
            edge=edge,
            rule=rule,
            length=length,
            time=time,
            heading_start=rule.vehicle_heading(travel_start),
            heading_end=rule.vehicle_heading(travel_end),
        )

    def _connect(self) -> None:
        leaving: dict[str, list[_Leg]] = {}
        for leg in self._legs.values():
            leaving.setdefault(leg.edge.start, []).append(leg)
        transitions: list[tuple[int, int, int]] = []

        def link(source: int, target: int, cost: float) -> None:
            transitions.append((source, target, self._weight(cost)))
            self._into.setdefault(target, []).append(len(self._weights) - 1)

        for leg in self._legs.values():
            node = self._nodes[leg.edge.end]
            theta = node.theta_for(self.profile)
            link(self._depart[leg.edge.start], leg.state, leg.time)
            arrival = turn_angle(leg.heading_end, theta, turn_directions(leg.rule.rotation_at_end))
            if arrival is not None:
                link(leg.state, self._arrive[node.node_id], self._turn_time(arrival, leg))
            for following in leaving.get(node.node_id, []):
                angle = self._turn(leg, following, theta)
                if angle is not None:
                    cost = self._turn_time(angle, following) + following.time
                    link(leg.state, following.state, cost)
        self._graph.add_edges_from(transitions)

    def _turn(self, arriving: _Leg, leaving: _Leg, theta: float | None) -> float | None:
        if arriving.rule.rotation_allowed or leaving.rule.rotation_allowed:
            return 0.0  # the vehicle turns while driving one of the edges
        directions = turn_directions(arriving.rule.rotation_at_end, leaving.rule.rotation_at_start)
        return turn_via(arriving.heading_end, theta, leaving.heading_start, directions)

    def _turn_time(self, angle: float, leg: _Leg) -> float:
        speeds = [s for s in (self.profile.rotation_speed, leg.rule.max_rotation_speed) if s]
        if not angle or self.profile.rotation_speed is None or not speeds:
            return 0.0
        return angle / min(speeds)

    def _weight(self, cost: float) -> int:
        self._weights.append(cost)
        return len(self._weights) - 1

    def _legs_from(self, node_id: str) -> list[_Leg]:
        return [self._legs[v] for _, v, _ in self._graph.out_edges(self._depart[node_id])]

    def _search(self, start: str, goal: str, weights: Sequence[float]) -> Route:
        target = self._arrive[goal]
        paths = rx.dijkstra_shortest_paths(
            self._graph, self._depart[start], target=target, weight_fn=weights.__getitem__
        )
        if target not in paths:
            raise NoRouteError(f"no route from {start} to {goal} for {self._who()}")
        return self._route_of(list(paths[target]), start)

    def _descend(self, path: list[int], table: array[float], target: int) -> list[int] | None:
        """Follow the distance table downhill from the end of `path` to `target`."""
        seen = set(path)
        state = path[-1]
        while state != target:
            options = [
                (self._weights[w] + table[v], table[v], v)
                for _, v, w in self._graph.out_edges(state)
                if v not in seen and not math.isinf(table[v])
            ]
            if not options:
                return None
            state = min(options)[2]
            path.append(state)
            seen.add(state)
        return path

    def _route_of(self, path: list[int], start: str, *, extra: float = 0.0) -> Route:
        legs = [self._legs[s] for s in path if s in self._legs]
        steps = zip(path, path[1:], strict=False)
        cost = extra + sum(self._weights[self._graph.get_edge_data(a, b)] for a, b in steps)
        nodes = [start] + [leg.edge.end for leg in legs]
        map_ids: list[str] = []
        for node_id in nodes:
            map_id = self._nodes[node_id].map_id
            if not map_ids or map_ids[-1] != map_id:
                map_ids.append(map_id)
        return Route(
            nodes=nodes,
            edges=[leg.edge.edge_id for leg in legs],
            travel_time=cost,
            length=sum(leg.length for leg in legs),
            map_ids=map_ids,
        )

    def _table(self, goal: str) -> array[float]:
        with self._lock:
            table = self._tables.get(goal)
            if table is not None:
                self._tables.move_to_end(goal)
                return table
            if self._reversed is None:
                self._reversed = self._reverse_matrix()
            seconds = dijkstra(self._reversed, directed=True, indices=self._arrive[goal])
            table = array("d")
            table.frombytes(np.ascontiguousarray(seconds, dtype=float).tobytes())
            table[self._arrive[goal]] = 0.0
            self._tables[goal] = table
            if len(self._tables) > TABLE_CACHE_SIZE:
                self._tables.popitem(last=False)
            return table

    def _reverse_matrix(self) -> csr_array:
        """The transitions reversed (row: the state entered, column: the state left) as a
        sparse matrix of weights. Zero weights stay stored entries, which csgraph takes for
        edges of weight 0 (tests/traffic/test_timegraph_tables.py); no two transitions join
        the same two states (parallel edges are separate legs), so none are added up."""
        size = self._graph.num_nodes()
        transitions = self._graph.weighted_edge_list()
        sources = np.fromiter((t[0] for t in transitions), dtype=np.int64, count=len(transitions))
        targets = np.fromiter((t[1] for t in transitions), dtype=np.int64, count=len(transitions))
        weights = np.fromiter(
            (self._weights[t[2]] for t in transitions), dtype=float, count=len(transitions)
        )
        return csr_array((weights, (targets, sources)), shape=(size, size))

    def _penalise(self, route: Route, weights: list[float], penalty: float) -> None:
        driven = set(route.edges)
        for state, leg in self._legs.items():
            if leg.edge.edge_id in driven:
                for transition in self._into.get(state, []):
                    weights[transition] *= 1.0 + penalty

    def _require(self, *node_ids: str) -> None:
        for node_id in node_ids:
            if node_id not in self._nodes:
                raise NoRouteError(f"unknown node {node_id}")
            if node_id not in self._depart:
                raise NoRouteError(f"node {node_id} is not usable by {self._who()}")

    def _who(self) -> str:
        vehicle_type = self.profile.vehicle_type
        return f"vehicle type {vehicle_type}" if vehicle_type else "any vehicle"
