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
from traffic.plans import Vehicle, node_hold_end
from traffic.reservations import Hold, ReservationTable
from traffic.sipp import ClassGraph


def stay(v: Vehicle, graph: ClassGraph, i: int) -> float:
    """Seconds the vehicle spends at route index i before leaving: dwell and turn."""
    seconds = graph.turn(v.headings[i], v.headings[i + 1])
    for (_, dwell), stop in zip(v.goals, v.stops, strict=True):
        if stop == i and i > v.passed:
            seconds += dwell
    return seconds


OVERSHOOT_MAX = 60.0  # s: the most a push with `growth` goes past the earliest departure


def lower_bounds(
    v: Vehicle, graph: ClassGraph, now: float, slack: float = 0.0, growth: float = 0.0
) -> tuple[float, int] | None:
    """The earliest departure from the vehicle's last reported node that is still possible.

    None while the plan is at most `slack` seconds too early; otherwise the bound plus `slack`
    (pushing a little further than needed makes the next push come later). With `growth`,
    a vehicle that has not reached a node for s seconds is pushed `growth`·s past the bound
    when that is more than `slack` (at most `OVERSHOOT_MAX`): a long wait is re-timed a few
    times with growing steps instead of every 2·slack seconds, each push moving its
    vehicle's whole remaining route and the holds queued behind it.
    """
    p = v.passed
    if v.static or p >= len(v.route) - 1:
        return None
    if v.base > p:  # driving to p + 1: it has not arrived yet
        earliest = now - graph.travel[(v.route[p], v.route[p + 1])]
    else:  # standing at its decision point (waiting, turning or handling)
        earliest = max(now, v.ready_at) + graph.turn(v.headings[p], v.headings[p + 1])
    if earliest <= v.depart[p] + slack:
        return None
    overshoot = max(slack, min(growth * (now - v.last_progress), OVERSHOOT_MAX))
    return earliest + overshoot, p


def propagate_plain(
    vehicles: Sequence[Vehicle],
    table: ReservationTable,
    graphs: Sequence[ClassGraph],
    pushes: list[tuple[float, int, int]],
    leave: float = -1.0,
) -> int:
    """Apply pushes (time, vehicle, index: no departure from that index before time).

    Returns the number of steps moved. (`propagate` is this or its compiled twin.) A node
    hold ends on arrival at the next node, or with `leave` >= 0 (grid rules) `leave` s after
    the departure (`plans.node_hold_end`).

    Steps are taken in the order of their planned departure before this call: every
    constraint points forward in that order (a vehicle's next step, the holds queued behind a
    hold), so each step is moved once, by the latest of its pushes. (Taken in the order of
    the push times instead, a step reached again by a later, larger push was walked again,
    and with it everything behind it: on S3 2 to 3 times as many moves.) The result is the
    same in any order: the earliest times that keep every constraint.
    """
    heap = [(vehicles[idx].depart[i], -t, idx, i) for t, idx, i in pushes]
    heapq.heapify(heap)
    moved = 0
    while heap:
        _, minus, idx, i = heapq.heappop(heap)
        t = -minus
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
            for hold, end in ((edge, arrive), (v.node_holds[i], node_hold_end(t, arrive, leave))):
                if hold.end < end:
                    hold.end = end
                    table.ended(hold)
                    _push_followers(vehicles, table, hold, idx, heap)
            moved += 1
            i += 1
            if i >= last:
                break
            ready = arrive + stay(v, graph, i)
            if ready <= v.depart[i]:
                break  # a planned wait absorbs the delay
            entry = (v.depart[i], -ready, idx, i)
            if heap and heap[0] < entry:  # another step comes first
                heapq.heappush(heap, entry)
                break
            t = ready  # the next step is the next in order: no need to queue it
    return moved


def _push_followers(
    vehicles: Sequence[Vehicle],
    table: ReservationTable,
    hold: Hold,
    idx: int,
    heap: list[tuple[float, float, int, int]],
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
            i = follower.index - 1
            heapq.heappush(heap, (vehicles[follower.vehicle].depart[i], -end, follower.vehicle, i))


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
