"""The SIPP search loop in plain Python: the reference, and the fallback when the compiled loop
(`traffic/_speedups.pyx`, built by `make venv`) is missing or stale.

Both take the same `Problem` and return the same answer, expansion for expansion (the heap
order is (f, -arrival, push count), a total order, so any heap pops the same sequence);
`tests/traffic/test_speedups.py` compares them on random problems.
"""

from __future__ import annotations

import heapq
import math
from collections.abc import Collection, Sequence
from dataclasses import dataclass
from typing import Any

INF = math.inf
SHIFT = 24  # bits of the interval index in a search key
UNIT = 1 << SHIFT

Chain = list[tuple[int, float, float]]  # (search key, arrival, departure) from the start on
Found = tuple[Chain, bool, bool]  # the chain, complete, ends at a refuge


@dataclass
class Problem:
    """One search, prepared by `traffic.sipp.search` (see there for the meaning)."""

    graph: Any  # traffic.sipp.ClassGraph
    table: Any  # traffic.reservations.ReservationTable
    vehicle: int
    start: int
    heading: int
    start_state: int  # the graph state at the start, or `outside` (graph.state_count)
    t0: float
    deadline: float
    goals: Sequence[tuple[int, float]]
    tables: list[Any]  # per stage: seconds to finish from each state (array of doubles)
    h_start: float
    partial: bool
    max_expansions: int
    weight: float
    refuge: bool
    avoid: Collection[int]
    refuge_cost: Sequence[float] | None
    # The compiled loop runs while other threads may use the table (`search(unlocked=...)`):
    # it must not sort the table's lists in place then (a sorted copy instead).
    shared: bool = False
    move_cost: Any = None  # s per move, flat in `graph.moves` order (`traffic.congestion`)
    leave: float = -1.0  # grid rules (>= 0): s a node stays held after the departure


def run(p: Problem) -> Found | None:
    """Search `p`; the chain of the path found, or None."""
    graph, goals, tables, weight, start, heading = (
        p.graph, p.goals, p.tables, p.weight, p.start, p.heading,
    )  # fmt: skip
    last = len(goals) - 1
    cache: dict[int, list[tuple[float, float]]] = {}
    safe_intervals, cost_to = p.table.safe_intervals, graph.cost_to
    node_of, key_of, moves = graph.node_of, graph.key_of, graph.moves
    outside = graph.state_count
    span = outside + 1
    start_key = p.start_state << SHIFT
    parents: dict[int, tuple[int, float]] = {start_key: (-1, -INF)}
    best: dict[int, float] = {start_key: p.t0}
    # With a move cost a state is better when its arrival plus cost is smaller; the cost is
    # kept beside (`spent`; 0 without a cost, which leaves every comparison as it was).
    move_cost, offsets = p.move_cost, graph.move_offsets
    spent: dict[int, float] = {}
    spent_get = spent.get
    h0 = p.t0 + weight * (p.h_start if p.h_start < INF else 0.0)
    heap = [(h0, -p.t0, 0, start_key, p.deadline, p.start_state, 0, 0.0)]
    nearest: tuple[float, float, int] | None = None
    pushes = expansions = 0
    pop, push, best_get = heapq.heappop, heapq.heappush, best.get
    partial, refuge, avoid, refuge_cost = p.partial, p.refuge, p.avoid, p.refuge_cost
    vehicle, leave = p.vehicle, p.leave
    while heap:
        _, neg_t, _, key, end, s, stage, c = pop(heap)
        t = -neg_t
        if best_get(key, INF) + spent_get(key, 0.0) < t + c:
            continue
        expansions += 1
        if expansions > p.max_expansions:
            break
        if s == outside:
            u, hk, out = start, heading, graph._moves(start, heading)
        else:
            u, hk, out = node_of[s], key_of[s], moves[s]
        if stage > last + 1:  # a refuge, popped in order of arrival plus its cost
            return _chain(parents, best, parents[key][0]), True, True
        if stage > last:  # the refuge stage
            if end == INF and u not in avoid:
                cost = refuge_cost[u] if refuge_cost is not None else 0.0
                if cost <= 0.0:
                    return _chain(parents, best, key), True, True
                child = key + span * UNIT
                if child not in best:
                    best[child] = t
                    spent[child] = c
                    parents[child] = (key, -INF)
                    pushes += 1
                    push(heap, (t + c + cost, -t, pushes, child, end, s, stage + 1, c))
        elif u == goals[stage][0]:
            if stage == last and not refuge:
                if end == INF:
                    return _chain(parents, best, key), True, False
            else:
                t2 = t + goals[stage][1]
                child = key + span * UNIT
                if t2 < end and t2 + c < best_get(child, INF) + spent_get(child, 0.0):
                    best[child] = t2
                    spent[child] = c
                    parents[child] = (key, -INF)  # a dwell, not a move
                    pushes += 1
                    h = tables[stage + 1][s] if s != outside else cost_to(tables[stage + 1], u, hk)
                    push(heap, (t2 + c + weight * h, -t2, pushes, child, end, s, stage + 1, c))
        if partial and end == INF and stage == last:
            score = tables[last][s] if s != outside else cost_to(tables[last], u, hk)
            if nearest is None or (score, t) < nearest[:2]:
                nearest = (score, t, key)
        table_h = tables[stage]
        base = stage * span
        first = offsets[s] if s != outside else -1  # (the start's own moves cost nothing)
        for i, (v, seg, tau, vs_, turning) in enumerate(out):
            h = table_h[vs_]
            if h == INF and not partial:
                continue
            earliest = t + turning
            latest = end - (tau if leave < 0 else leave)  # u is held until then
            if earliest > latest:
                continue
            node_gaps = cache.get(v)
            if node_gaps is None:
                node_gaps = cache[v] = safe_intervals(v, vehicle)
            seg_gaps = cache.get(seg)
            if seg_gaps is None:
                seg_gaps = cache[seg] = safe_intervals(seg, vehicle)
            child_base = (base + vs_) << SHIFT
            cc = c + move_cost[first + i] if move_cost is not None and first >= 0 else c
            for ws, we in seg_gaps:
                if ws > latest:
                    break
                lo = earliest if earliest > ws else ws
                hi = latest if latest < we - tau else we - tau
                if lo > hi:
                    continue
                for idx, (vs, ve) in enumerate(node_gaps):
                    if vs > hi:
                        break
                    dep = lo if lo > vs else vs
                    arrive = dep + tau
                    if dep > hi or arrive >= ve:
                        continue
                    child = child_base + idx + 1
                    if arrive + cc < best_get(child, INF) + spent_get(child, 0.0):
                        best[child] = arrive
                        spent[child] = cc
                        parents[child] = (key, dep)
                        pushes += 1
                        f = arrive + cc + weight * (h if h < INF else 0.0)
                        push(heap, (f, -arrive, pushes, child, ve, vs_, stage, cc))
    if partial and nearest is not None and nearest[2] != start_key:
        return _chain(parents, best, nearest[2]), False, False
    return None


def _chain(parents: dict[int, tuple[int, float]], best: dict[int, float], key: int) -> Chain:
    chain: Chain = []
    current = key
    while current >= 0:
        parent, dep = parents[current]
        chain.append((current, best[current], dep))
        current = parent
    chain.reverse()
    return chain
