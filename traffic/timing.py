"""Re-timing after delays (keep planned times realistic, never change an order); cycle checks.

Plans are made in plan time; a vehicle that falls behind (a slow move, a wait at its decision
point) makes every planned time of its rest, and of whoever is queued behind it, too early. Stale
times hurt twice: new plans treat resources as free that are not, and a vehicle waiting for a
late one cannot be re-planned ahead of it. Re-timing pushes times later, monotonically:

    depart[i] >= arrive[i] + turn + dwell           (the vehicle's own pace)
    start(Y) >= end(X) for X queued before Y        (the order of every conflict set)

A push at one step moves the vehicle's later steps until its planned waits absorb it, and pushes
the holds queued behind each hold whose end moved. Orders never change and conflicting holds
never overlap, so the dependency graph stays acyclic; lists whose keys moved are re-sorted
(lazily, stable) before the next plan is inserted.
"""

from __future__ import annotations

import heapq
from collections.abc import Sequence

from traffic import speedups
from traffic.plans import Vehicle
from traffic.reservations import Hold, ReservationTable
from traffic.sipp import ClassGraph


def stay(v: Vehicle, graph: ClassGraph, i: int) -> float:
    """Seconds the vehicle spends at route index i before leaving: dwell and turn."""
    seconds = graph.turn(v.headings[i], v.headings[i + 1])
    for (_, dwell), stop in zip(v.goals, v.stops, strict=True):
        if stop == i and i > v.passed:
            seconds += dwell
    return seconds


def lower_bounds(
    v: Vehicle, graph: ClassGraph, now: float, slack: float = 0.0
) -> tuple[float, int] | None:
    """The earliest departure from the vehicle's last reported node that is still possible.

    None while the plan is at most `slack` seconds too early; otherwise the bound plus `slack`
    (pushing a little further than needed makes the next push come later).
    """
    p = v.passed
    if v.static or p >= len(v.route) - 1:
        return None
    if v.base > p:  # driving to p + 1: it has not arrived yet
        earliest = now - graph.travel[(v.route[p], v.route[p + 1])]
    else:  # standing at its decision point (waiting, turning or handling)
        earliest = max(now, v.ready_at) + graph.turn(v.headings[p], v.headings[p + 1])
    return (earliest + slack, p) if earliest > v.depart[p] + slack else None


def propagate_plain(
    vehicles: Sequence[Vehicle],
    table: ReservationTable,
    graphs: Sequence[ClassGraph],
    pushes: list[tuple[float, int, int]],
) -> int:
    """Apply pushes (time, vehicle, index: no departure from that index before time).

    Returns the number of steps moved. (`propagate` is this or its compiled twin.)
    """
    heap = list(pushes)
    heapq.heapify(heap)
    moved = 0
    while heap:
        t, idx, i = heapq.heappop(heap)
        v = vehicles[idx]
        last = len(v.route) - 1
        if i >= last or t <= v.depart[i]:
            continue
        graph = graphs[v.cls]
        while True:
            v.depart[i] = t
            arrive = t + graph.travel[(v.route[i], v.route[i + 1])]
            edge, node = v.edge_holds[i + 1], v.node_holds[i + 1]
            assert edge is not None
            for hold in (edge, node):
                if hold.start < t:
                    hold.start = t
                    table.retimed(hold)
            v.arrive[i + 1] = arrive
            for hold in (edge, v.node_holds[i]):
                if hold.end < arrive:
                    hold.end = arrive
                    table.ended(hold)
                    _push_followers(table, hold, idx, heap)
            moved += 1
            i += 1
            if i >= last:
                break
            ready = arrive + stay(v, graph, i)
            if ready <= v.depart[i]:
                break  # a planned wait absorbs the delay
            t = ready
    return moved


def _push_followers(
    table: ReservationTable, hold: Hold, idx: int, heap: list[tuple[float, int, int]]
) -> None:
    """Push the other vehicles' holds queued behind `hold` that now start before it ends."""
    queue = table.blocked[hold.resource]
    try:
        position = queue.index(hold)
    except ValueError:
        return  # already cleared
    end = hold.end
    ordered = hold.resource not in table.unsorted  # then keys ascend: stop at the first >= end
    for k in range(position + 1, len(queue)):
        follower = queue[k]
        if follower.key >= end and ordered:
            break
        if follower.vehicle != idx and not follower.released and follower.start < end:
            heapq.heappush(heap, (end, follower.vehicle, follower.index - 1))


propagate = speedups.COMPILED.propagate if speedups.COMPILED else propagate_plain


def find_cycles(graph: dict[str, list[str]]) -> list[list[str]]:
    """The cycles a depth-first search meets in a wait-for graph (vehicle -> whom it waits for)."""
    cycles: list[list[str]] = []
    state: dict[str, int] = {}  # 1: on the current path, 2: done
    for root in graph:
        if state.get(root):
            continue
        stack: list[tuple[str, int]] = [(root, 0)]
        trail: list[str] = []
        while stack:
            name, i = stack.pop()
            if i == 0:
                state[name] = 1
                trail.append(name)
            successors = graph.get(name, [])
            if i < len(successors):
                stack.append((name, i + 1))
                nxt = successors[i]
                if state.get(nxt) == 1:
                    cycles.append(trail[trail.index(nxt) :])
                elif not state.get(nxt):
                    stack.append((nxt, 0))
            else:
                state[name] = 2
                trail.pop()
    return cycles
