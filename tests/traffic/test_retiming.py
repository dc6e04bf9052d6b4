"""Re-timing takes steps in planned-departure order: the same times as a walk in push-time order
(the earliest times that keep every constraint), with each step moved once."""

import heapq
from collections.abc import Callable, Sequence
from typing import Any

import pytest

import traffic.manager
from tests.traffic.helpers import cells, manager
from tests.traffic.test_planning_speed import busy_grid
from traffic import timing
from traffic.layout import Layout
from traffic.plans import Goal, Vehicle
from traffic.reservations import ReservationTable
from traffic.sipp import ClassGraph

Propagate = Callable[
    [Sequence[Vehicle], ReservationTable, Sequence[ClassGraph], list[tuple[float, int, int]]], int
]


def time_ordered(
    vehicles: Sequence[Vehicle],
    table: ReservationTable,
    graphs: Sequence[ClassGraph],
    pushes: list[tuple[float, int, int]],
    leave: float = -1.0,
) -> int:
    """The re-timing of the seventh round: pushes in time order, each walked to its end
    (footprint rules only: `leave` < 0)."""
    assert leave < 0
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
                    queue = table.blocked[hold.resource]
                    if hold in queue:
                        for follower in queue[queue.index(hold) + 1 :]:
                            if (
                                follower.vehicle != idx
                                and not follower.released
                                and follower.start < arrive
                            ):
                                heapq.heappush(heap, (arrive, follower.vehicle, follower.index - 1))
            moved += 1
            i += 1
            if i >= last:
                break
            ready = arrive + timing.stay(v, graph, i)
            if ready <= v.depart[i]:
                break
            t = ready
    return moved


def retimed_run(
    monkeypatch: pytest.MonkeyPatch, propagate: Propagate, **options: object
) -> tuple[list[Any], int]:
    """The delayed busy grid re-timed by `propagate`: [outcome, tasks done, plans, holds]
    and the steps moved."""
    moved = 0

    def counting(*args: Any) -> int:
        nonlocal moved
        steps = propagate(*args)
        moved += steps
        return steps

    monkeypatch.setattr(traffic.manager, "propagate", counting)
    m, sim, tasks = busy_grid(**options)
    stats = sim.run(400.0)
    plans = {v.name: (v.route, v.arrive, v.depart) for v in m._vehicles}
    holds = sorted(repr(h) for queue in m.table.blocked for h in queue)
    outcome = [repr(stats.tasks), stats.collisions, stats.moves, stats.delays, stats.waits]
    outcome += [stats.wait_cycles, stats.stalls]
    return [outcome, tasks.done, plans, holds], moved


@pytest.mark.parametrize("propagate", [timing.propagate, timing.propagate_plain])
def test_departure_order_gives_the_times_of_a_walk_in_push_order(
    monkeypatch: pytest.MonkeyPatch, propagate: Propagate
) -> None:
    reference, walked = retimed_run(monkeypatch, time_ordered)
    result, moved = retimed_run(monkeypatch, propagate)
    assert result == reference
    assert reference[0][1] == 0  # no collisions
    assert 0 < moved < walked  # here 205 steps moved instead of 271


def test_a_long_wait_is_pushed_further_with_growth() -> None:
    m = manager(Layout.grid(cells(["......"])), {"A": "0,0"})
    m.plan("A", [Goal("0,5")], 0.0)
    v, graph = m.vehicle("A"), m.graphs[0]
    assert v.base > v.passed == 0  # released, driving to index 1 (no progress since t = 0)
    tau = graph.travel[(v.route[0], v.route[1])]
    earliest = 40.0 - tau  # at 40 s it is still on the way: it cannot have left before
    assert timing.lower_bounds(v, graph, 40.0, 2.0) == (earliest + 2.0, 0)
    assert timing.lower_bounds(v, graph, 40.0, 2.0, 0.5) == (earliest + 20.0, 0)  # 0.5 · 40 s
    assert timing.lower_bounds(v, graph, 6.0, 2.0, 0.25) == (6.0 - tau + 2.0, 0)  # 1.5 < slack
    assert timing.lower_bounds(v, graph, 400.0, 2.0, 0.5) == (400.0 - tau + timing.OVERSHOOT_MAX, 0)
    assert timing.lower_bounds(v, graph, 0.5, 2.0, 0.5) is None  # not late beyond the slack


def test_growth_pushes_long_waits_less_often_and_stays_safe() -> None:
    def run(growth: float) -> tuple[int, int]:
        m, sim, tasks = busy_grid(retime_growth=growth)
        pushes = 0
        original = traffic.manager.propagate

        def counting(*args: Any) -> int:
            nonlocal pushes
            pushes += len(args[3])
            return original(*args)

        traffic.manager.propagate = counting
        try:
            stats = sim.run(400.0)
        finally:
            traffic.manager.propagate = original
        assert stats.collisions == 0
        assert stats.wait_cycles == 0
        assert stats.stalls == 0
        return sum(tasks.done.values()), pushes

    done, pushes = run(0.0)
    grown_done, grown_pushes = run(0.5)
    assert grown_done == done == 15
    assert grown_pushes < pushes
