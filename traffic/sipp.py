"""Safe Interval Path Planning (Phillips & Likhachev 2011) on a layout, with turning and stops.

The search state is (node, heading, safe interval, goal stage); its value is the earliest arrival
in that interval. A move u -> v departing at t and arriving at t + tau needs:

- the vehicle's interval at u to last until t + tau (it occupies u until it reaches v; under
  grid rules, `leave` >= 0, only until t + leave);
- the segment u-v to be free during [t, t + tau];
- v to be free from t on (the step into v is claimed when the vehicle sets off).

Waiting is implicit (departing later within the interval), turning on the spot costs
angle / rotation speed before departure. Goals are visited in order with a dwell time each (pick,
drop); the last goal needs an interval that never ends, because the vehicle stays there until it
gets its next plan. With `refuge` (opt-in, lifelong task streams) the last goal needs only a
visit: the path goes on from it to the nearest node where the vehicle may stay for good (its
refuge), so a goal someone reaches later is no reason to fail. Heuristic: the exact time for the
rest of the tour, turning and dwells
included, as if the vehicle were alone (reverse-Dijkstra tables over (node, heading) states).
"""

from __future__ import annotations

import math
from array import array
from collections import OrderedDict
from collections.abc import Callable, Collection, Sequence
from contextlib import AbstractContextManager
from dataclasses import dataclass
from typing import Any

import numpy as np
from scipy.sparse import csr_matrix
from scipy.sparse.csgraph import dijkstra

from traffic import sipp_loop, speedups
from traffic.footprint import VehicleClass
from traffic.layout import Layout
from traffic.reservations import ReservationTable
from traffic.sipp_loop import SHIFT, Chain, Problem

INF = math.inf
ANY_HEADING = -1  # a heading key that turns for free (a vehicle whose heading is unknown)
HEADING_STEPS = 3600  # heading keys per full turn (0.1°)
TABLE_CACHE = 256  # heuristic tables kept per vehicle class
ZERO = 1e-9  # s: a zero-cost edge in the sparse graph (scipy drops explicit zeros)


@dataclass(frozen=True)
class Path:
    """A timed route: node indices with arrival and departure times, and where the goals are."""

    nodes: list[int]
    arrive: list[float]
    depart: list[float]  # inf for the last node
    headings: list[int]  # heading key on arrival (ANY_HEADING for an unknown start heading)
    stops: list[int]  # route index at which each goal was served
    complete: bool = True  # False: a partial path towards an unreachable goal


class ClassGraph:
    """The layout as one vehicle class drives it: successors with travel times and headings.

    Heuristic tables are exact travel times to a goal over (node, heading) states, turning
    included but other vehicles ignored: one reverse Dijkstra (scipy) per goal, cached.
    """

    def __init__(self, layout: Layout, vehicle: VehicleClass, *, cache: int = TABLE_CACHE):
        self.layout = layout
        self.vehicle = vehicle
        self.turning = vehicle.rotation_speed is not None
        self.succ: list[list[tuple[int, int, float, int]]] = [[] for _ in layout.node_ids]
        self.travel: dict[tuple[int, int], float] = {}
        self.states: list[dict[int, int]] = [{} for _ in layout.node_ids]  # node -> key -> state
        self._turns: dict[tuple[int, int], float] = {}
        count = 0
        for e, edge in enumerate(layout.edges):
            speeds = [s for s in (vehicle.speed, edge.max_speed) if s]
            tau = edge.length / min(speeds)
            key = heading_key(edge.heading) if self.turning else 0
            self.succ[edge.start].append((edge.end, layout.segment_resource(e), tau, key))
            self.travel[(edge.start, edge.end)] = tau
            if key not in self.states[edge.end]:
                self.states[edge.end][key] = count
                count += 1
        for keys in self.states:
            if not keys:
                keys[0] = count  # a node nobody drives into still gets a state
                count += 1
        self.state_count = count
        # per state: its node, heading key and moves (node, segment, travel, state, turn) with
        # the turn precomputed: the search loop then does no dict or function lookups
        self.node_of = [0] * count
        self.key_of = [0] * count
        for v, keys in enumerate(self.states):
            for key, state in keys.items():
                self.node_of[state], self.key_of[state] = v, key
        self.moves: list[list[tuple[int, int, float, int, float]]] = [
            self._moves(self.node_of[s], self.key_of[s]) for s in range(count)
        ]
        # where each state's moves begin in the flat move order (a move cost's index)
        self.move_offsets = [0] * (count + 1)
        for s in range(count):
            self.move_offsets[s + 1] = self.move_offsets[s] + len(self.moves[s])
        arrive = count  # arrive(v) = count + v, the goal "whatever the heading"
        reverse: list[tuple[int, int, float]] = []
        for v, keys in enumerate(self.states):
            for key, state in keys.items():
                reverse.append((arrive + v, state, 0.0))
                for w, _, tau, w_key in self.succ[v]:
                    cost = self.turn(key, w_key) + tau
                    reverse.append((self.states[w][w_key], state, cost))
        size = count + layout.node_count
        rows, cols, costs = zip(*reverse, strict=True) if reverse else ((), (), ())
        weights = np.maximum(np.asarray(costs, dtype=float), ZERO)  # explicit zeros are no edge
        self._reverse = csr_matrix((weights, (rows, cols)), shape=(size, size))
        self._reverse.sum_duplicates()
        self._tables: OrderedDict[tuple[tuple[int, float], ...], array[float]] = OrderedDict()
        self._cache = cache
        self.zeros = array("d", [0.0]) * count  # the estimate of a refuge stage

    def _moves(self, node: int, key: int) -> list[tuple[int, int, float, int, float]]:
        return [
            (w, seg, tau, self.states[w][w_key], self.turn(key, w_key))
            for w, seg, tau, w_key in self.succ[node]
        ]

    def __getstate__(self) -> dict[str, Any]:
        """Pickled without its caches, which are rebuilt as searches need them (the compiled
        search's move arrays, the heuristic tables): a long benchmark run is saved and resumed
        whole (`bench.traffic --resume`), the same run either way."""
        state = self.__dict__.copy()
        state.pop("_native_moves", None)
        state["_tables"] = OrderedDict()
        return state

    def state(self, node: int, key: int) -> int:
        """The state of `node` entered with heading `key`, or -1 if no edge enters it so."""
        return self.states[node].get(key, -1)

    def to(self, goal: int) -> array[float]:
        """Seconds to `goal` from every (node, heading) state, alone on the layout (cached)."""
        return self.tour([(goal, 0.0)])[0]

    def tour(self, goals: Sequence[tuple[int, float]]) -> list[array[float]]:
        """Per goal stage, seconds to finish the tour (goals with dwells) from every state.

        The table of stage j starts the reverse Dijkstra at goal j's states, each seeded with the
        dwell plus the rest of the tour from that heading, so it is exact (others ignored).
        """
        tables: list[array[float]] = []
        following: array[float] | None = None
        for j in range(len(goals) - 1, -1, -1):
            key = tuple(goals[j:])
            table = self._tables.get(key)
            if table is None:
                table = self._dijkstra(goals[j][0], goals[j][1], following)
                self._tables[key] = table
                if len(self._tables) > self._cache:
                    self._tables.popitem(last=False)
            else:
                self._tables.move_to_end(key)
            tables.append(table)
            following = table
        tables.reverse()
        return tables

    def _dijkstra(self, goal: int, dwell: float, following: array[float] | None) -> array[float]:
        """Reverse Dijkstra (scipy, C speed) from goal's arrival node.

        For an intermediate goal the arrival node's edges into the goal's states temporarily
        weigh the dwell plus the rest of the tour from each heading.
        """
        graph = self._reverse
        source = self.state_count + goal
        lo, hi = graph.indptr[source], graph.indptr[source + 1]
        saved = graph.data[lo:hi].copy()
        if following is not None:
            rest = np.frombuffer(following, dtype=float)[graph.indices[lo:hi]]
            graph.data[lo:hi] = np.maximum(dwell + rest, ZERO)
        try:
            seconds = dijkstra(graph, directed=True, indices=source)
        finally:
            graph.data[lo:hi] = saved
        table = array("d")
        table.frombytes(np.ascontiguousarray(seconds[: self.state_count]).tobytes())
        if following is None:
            for state in self.states[goal].values():
                table[state] = 0.0
        return table

    def cost_to(self, table: array[float], node: int, key: int) -> float:
        """Seconds from `node` with heading `key` (ANY_HEADING: the best heading) via `table`."""
        keys = self.states[node]
        if key in keys:
            return table[keys[key]]
        best = min(table[s] for s in keys.values())  # a lower bound
        for w, _, tau, w_key in self.succ[node]:
            best = min(best, self.turn(key, w_key) + tau + table[self.states[w][w_key]])
        return best

    def turn(self, start: int, end: int) -> float:
        """Seconds to turn on the spot from heading key `start` to `end`."""
        if start < 0 or not self.turning or start == end:
            return 0.0
        cached = self._turns.get((start, end))
        if cached is None:
            steps = abs(end - start) % HEADING_STEPS
            angle = min(steps, HEADING_STEPS - steps) * math.tau / HEADING_STEPS
            cached = self._turns[(start, end)] = angle / (self.vehicle.rotation_speed or 1.0)
        return cached


def heading_key(angle: float) -> int:
    """An angle (rad) as an integer key, 0.1° resolution."""
    return round(math.degrees(angle) * 10) % HEADING_STEPS


def search(
    graph: ClassGraph,
    table: ReservationTable,
    vehicle: int,
    start: int,
    heading: int,
    t0: float,
    deadline: float,
    goals: Sequence[tuple[int, float]],
    *,
    partial: bool = False,
    max_expansions: int = 200_000,
    weight: float = 1.0,
    refuge: bool = False,
    avoid: Collection[int] = (),
    refuge_cost: Sequence[float] | None = None,
    move_cost: Sequence[float] | np.ndarray | None = None,
    leave: float = -1.0,
    unlocked: Callable[[], AbstractContextManager[object]] | None = None,
) -> Path | None:
    """The earliest-arriving path through `goals` (node, dwell) for `vehicle`, or None.

    The vehicle stands at `start` with `heading` from `t0` and must leave it before `deadline`
    (another vehicle is queued there). With `partial`, a path that cannot reach the last goal
    ends instead at the reachable node nearest to it where the vehicle may stay. A `weight`
    above 1 inflates the heuristic (weighted A*: faster, at most that factor from the earliest
    arrival). With `refuge`, the last goal is only visited (its dwell included) and the path
    ends at the earliest reachable node, not in `avoid`, where the vehicle may stay for good
    (`Path.stops` then holds the goals only); `refuge_cost` (s per node) makes busy nodes worse
    refuges: the refuge minimises arrival plus its cost. `move_cost` (s per move, flat in
    `ClassGraph.moves` order; `traffic.congestion`) is added to the arrival where the search
    compares and orders states: the path minimises arrival plus cost, its times stay exact.
    With `leave` >= 0 (grid rules) a node is held only until `leave` s after the departure.
    The loop runs compiled when `traffic._speedups` is built (`make venv`), in plain Python
    otherwise (same result).

    The compiled loop changes nothing shared and offers the GIL every few dozen expansions, so
    it runs inside `unlocked()`: the caller may let other threads at the table meanwhile (and
    must check the path against the table afterwards, `TrafficManager`). The plain loop fills
    the table's caches as it reads, so it always runs as called.
    """
    tables = graph.tour(goals)
    if refuge:  # the refuge stage (any node will do, no estimate), then refuges by cost
        tables += [graph.zeros, graph.zeros]
    h_start = graph.cost_to(tables[0], start, heading)
    if h_start == INF and not partial:
        return None
    gaps = table.safe_intervals(goals[-1][0], vehicle)
    if (not gaps or gaps[-1][1] != INF) and not partial and not refuge:
        return None  # someone stays on the last goal for good
    start_state = graph.state(start, heading)
    problem = Problem(
        graph, table, vehicle, start, heading,
        start_state if start_state >= 0 else graph.state_count,
        t0, deadline, goals, tables, h_start, partial, max_expansions, weight, refuge,
        avoid, refuge_cost, move_cost=move_cost, leave=leave,
    )  # fmt: skip
    if unlocked is not None and LOOP is not sipp_loop:
        problem.shared = True
        with unlocked():
            found = LOOP.run(problem)
    else:
        found = LOOP.run(problem)
    if found is None:
        return None
    chain, complete, to_refuge = found
    return _path(graph, chain, complete, start, heading, to_refuge)


def _path(
    graph: ClassGraph, chain: Chain, complete: bool, start: int, heading: int, refuge: bool
) -> Path:
    span = graph.state_count + 1
    nodes: list[int] = []
    arrive: list[float] = []
    depart: list[float] = []
    headings: list[int] = []
    stops: list[int] = []
    for k, t, dep in chain:
        if nodes and dep == -INF:
            stops.append(len(nodes) - 1)  # dwell at a goal on the way
            continue
        s = (k >> SHIFT) % span
        u, hk = (start, heading) if s == graph.state_count else (graph.node_of[s], graph.key_of[s])
        if nodes:
            depart.append(dep)
        nodes.append(u)
        arrive.append(t)
        headings.append(hk)
    depart.append(INF)
    if complete and not refuge:  # (a refuge path has recorded its last goal as a dwell)
        stops.append(len(nodes) - 1)
    return Path(nodes, arrive, depart, headings, stops, complete)


LOOP: Any = speedups.COMPILED or sipp_loop  # the search loop: compiled when built
