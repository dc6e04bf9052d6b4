"""A congestion cost for the search: what a route does to the plans made after it (opt-in).

Prioritized planning sees the plans made before it exactly (the reservation table), but nothing
tells a plan what it leaves the plans made after it: a route through a node many planned routes
enter, or head-on against a planned flow in a one-cell lane, leaves later plans long waits.
`FlowCost` counts, at most once per `refresh` seconds, how many steps of the vehicles'
remaining routes drive each directed edge and enter each node, and gives each search a cost
per move of its class graph (flat, in `ClassGraph.moves` order):

    against · (planned steps the other way along the move's edge)
    + through · (planned steps into the move's end node),

the searching vehicle's own route not counted. The search (`traffic.sipp.search(move_cost=...)`)
orders by arrival plus cost and keeps the times exact, so safety is untouched: a cost only
chooses among safe paths.
"""

from __future__ import annotations

import math
from collections.abc import Iterable

import numpy as np

from traffic.layout import Layout
from traffic.plans import Vehicle
from traffic.sipp import ClassGraph


class FlowCost:
    """Per class graph, the cost of each move from the planned flow (see the module)."""

    def __init__(
        self, layout: Layout, graph: ClassGraph, *, against: float, through: float,
        refresh: float = 1.0,
    ) -> None:  # fmt: skip
        self.against, self.through, self.refresh = against, through, refresh
        edge_of = {(e.start, e.end): i for i, e in enumerate(layout.edges)}
        to_node: list[int] = []
        reverse_edge: list[int] = []  # per move: the edge the other way, or -1
        for s, moves in enumerate(graph.moves):
            u = graph.node_of[s]
            for v, *_ in moves:
                to_node.append(v)
                reverse_edge.append(edge_of.get((v, u), -1))
        self.to_node = np.asarray(to_node, dtype=np.int64)
        self.reverse_edge = np.asarray(reverse_edge, dtype=np.int64)
        keys = np.asarray(
            [e.start * layout.node_count + e.end for e in layout.edges], dtype=np.int64
        )
        order = np.argsort(keys)
        self._edge_keys, self._edge_ids = keys[order], order  # sorted (from, to) keys
        self._edge_count = len(layout.edges)
        self._node_count = layout.node_count
        self._base = np.zeros(len(to_node))
        self._counted_at = -math.inf
        # the moves into each node, and along each edge's reverse (CSR): own steps are taken
        # out of the base where they count, not by a second pass over every move
        self._into = _grouped(self.to_node, self._node_count)
        self._against = _grouped(self.reverse_edge, self._edge_count)

    def costs(self, vehicles: Iterable[Vehicle], own: Vehicle, now: float) -> np.ndarray:
        """Seconds per move for `own`'s search: the flow of every vehicle's remaining route
        (counted again when `refresh` s have passed), `own`'s own steps taken out."""
        if now >= self._counted_at + self.refresh:
            self._base = self._cost(_steps(vehicles))
            self._counted_at = now
        start, end = _steps((own,))
        if not len(end):
            return self._base
        cost: np.ndarray = self._base.copy()
        if self.through:
            np.subtract.at(cost, _members(*self._into, end), self.through)
        if self.against:
            edges = self._edge_index(start, end)
            np.subtract.at(cost, _members(*self._against, edges), self.against)
        np.maximum(cost, 0.0, out=cost)  # (the base may predate own's latest route)
        return cost

    def _cost(self, steps: tuple[np.ndarray, np.ndarray]) -> np.ndarray:
        """The cost per move of these planned steps (from, to)."""
        start, end = steps
        entered = np.bincount(end, minlength=self._node_count).astype(float)
        edge = self._edge_index(start, end)
        driven = np.bincount(edge, minlength=self._edge_count + 1).astype(float)
        driven[self._edge_count] = 0.0  # the last slot: "no edge", always 0
        return self.through * entered[self.to_node] + self.against * driven[self.reverse_edge]

    def _edge_index(self, start: np.ndarray, end: np.ndarray) -> np.ndarray:
        """The edge of each step (from, to), or `edge_count` where there is none."""
        keys = start * self._node_count + end
        at = np.searchsorted(self._edge_keys, keys)
        at = np.minimum(at, len(self._edge_keys) - 1)
        found = self._edge_keys[at] == keys
        return np.where(found, self._edge_ids[at], self._edge_count)


def _steps(vehicles: Iterable[Vehicle]) -> tuple[np.ndarray, np.ndarray]:
    """The (from, to) nodes of the steps the vehicles have not yet passed, as two arrays."""
    starts: list[np.ndarray] = []
    ends: list[np.ndarray] = []
    for v in vehicles:
        if v.passed + 1 < len(v.route):
            nodes = np.asarray(v.route[v.passed :], dtype=np.int64)
            starts.append(nodes[:-1])
            ends.append(nodes[1:])
    if not starts:
        return np.zeros(0, dtype=np.int64), np.zeros(0, dtype=np.int64)
    start, end = np.concatenate(starts), np.concatenate(ends)
    moved = start != end
    return start[moved], end[moved]


def _grouped(keys: np.ndarray, size: int) -> tuple[np.ndarray, np.ndarray]:
    """Per key 0..size-1 the indices where `keys` holds it, as (pointers, indices)."""
    order = np.argsort(keys, kind="stable")
    pointers = np.searchsorted(keys[order], np.arange(size + 1))
    return pointers, order


def _members(pointers: np.ndarray, indices: np.ndarray, keys: np.ndarray) -> np.ndarray:
    """The indices of every key in `keys` (repeated as often as the key is), concatenated;
    a key out of range (`size`: no edge) has none."""
    keys = keys[keys < len(pointers) - 1]
    first, last = pointers[keys], pointers[keys + 1]
    lengths = last - first
    if not lengths.sum():
        return np.zeros(0, dtype=np.int64)
    offsets = np.repeat(first - np.cumsum(lengths) + lengths, lengths)
    found: np.ndarray = indices[offsets + np.arange(lengths.sum())]
    return found
