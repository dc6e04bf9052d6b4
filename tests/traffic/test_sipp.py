"""Prioritized SIPP: collision-free timed plans on small layouts."""

import itertools
import math

import pytest

from tests.traffic.helpers import AMR, cells, manager, simulate
from traffic.des import SimConfig, free_flow_time
from traffic.layout import Layout
from traffic.manager import NoPlanError, TrafficManager
from traffic.plans import Goal
from traffic.reservations import Hold


def overlaps(m: TrafficManager) -> list[tuple[Hold, Hold]]:
    """Pairs of different vehicles' holds on conflicting resources with overlapping times."""
    holds = {id(h): h for queue in m.table.blocked for h in queue}.values()
    found = []
    for a, b in itertools.combinations(holds, 2):
        if a.vehicle == b.vehicle or not m.conflicts.conflict(0, a.resource, b.resource):
            continue
        a_start = -math.inf if a.released else a.start
        b_start = -math.inf if b.released else b.start
        if a_start < b.end and b_start < a.end:
            found.append((a, b))
    return found


def test_a_lone_vehicle_drives_the_quickest_route_with_turns() -> None:
    layout = Layout.grid(cells(["....", "@@@.", "...."]))
    m = manager(layout, {"a": "0,0"})
    plan = m.plan("a", "2,0", 0.0)
    assert plan.nodes[0] == "0,0"
    assert plan.nodes[-1] == "2,0"
    assert len(plan.nodes) == 9  # 3 east, 2 south, 3 west
    assert plan.arrive[-1] == pytest.approx(8 + 2)  # 8 m, two 90° turns of 1 s
    assert free_flow_time(m, 0, layout.node("0,0"), 0, [Goal("2,0")]) == plan.arrive[-1]


def test_goals_are_visited_in_order_with_their_dwell() -> None:
    layout = Layout.grid([(0, c) for c in range(6)])
    m = manager(layout, {"a": "0,0"})
    plan = m.plan("a", [Goal("0,4", 5.0), Goal("0,1", 5.0)], 0.0)
    assert plan.nodes == ("0,0", "0,1", "0,2", "0,3", "0,4", "0,3", "0,2", "0,1")
    assert plan.stops == (4, 7)
    assert plan.depart[4] - plan.arrive[4] == pytest.approx(5 + 2)  # pick, then turn round


def test_intersection_crossing_plans_never_overlap() -> None:
    layout = Layout.grid(cells(["@@.@@", "@@.@@", ".....", "@@.@@", "@@.@@"]))
    m = manager(layout, {"ew": "2,0", "ns": "0,2"})
    m.vehicle("ns").headings[0] = m.graphs[0].succ[layout.node("0,2")][0][3]  # facing south
    first = m.plan("ew", "2,4", 0.0)
    second = m.plan("ns", "4,2", 0.0)
    assert "2,2" in first.nodes
    assert "2,2" in second.nodes
    assert overlaps(m) == []
    crossing_ew = first.nodes.index("2,2")
    crossing_ns = second.nodes.index("2,2")
    # the second vehicle reaches the crossing only after the first is a node beyond it
    assert second.depart[crossing_ns - 1] >= first.arrive[crossing_ew + 1]


def test_head_on_in_a_single_lane_waits_until_the_lane_is_clear() -> None:
    layout = Layout.grid([(0, c) for c in range(7)] + [(1, 3)])
    m = manager(layout, {"a": "0,0", "b": "1,3"})
    a = m.plan("a", "0,6", 0.0)
    b = m.plan("b", "0,0", 0.0)
    assert overlaps(m) == []
    # b may enter the lane at 0,3 only once a has left it behind (a at 0,4 clears 0,3)
    assert b.depart[0] >= a.arrive[a.nodes.index("0,4")]
    assert b.nodes == ("1,3", "0,3", "0,2", "0,1", "0,0")


def test_head_on_takes_a_parallel_lane_when_that_is_quicker() -> None:
    layout = Layout.grid(cells([".......", ".@@@@@.", "......."]))
    m = manager(layout, {"a": "0,0", "b": "0,6"})
    m.plan("a", "0,5", 0.0)
    with pytest.raises(NoPlanError):
        m.plan("b", "0,5", 0.0)  # a parks there for good: no plan can end there
    b = m.plan("b", "0,1", 0.0)
    assert overlaps(m) == []
    assert any(node.startswith("2,") for node in b.nodes)  # round the block


def test_corridor_swap_with_a_siding_completes_both_tasks() -> None:
    layout = Layout.grid([(0, c) for c in range(7)] + [(1, 3)], parking=[(1, 3)])
    stats, tasks = simulate(
        layout, {"a": "0,0", "b": "0,6"}, {"a": [[Goal("0,6")]], "b": [[Goal("0,0")]]}
    )
    assert tasks.done == {"a": 1, "b": 1}
    assert stats.collisions == 0
    assert stats.wait_cycles == 0
    assert stats.stalls == 0


def test_many_vehicles_on_a_small_grid_with_delays_stay_collision_free() -> None:
    layout = Layout.grid({(r, c) for r in range(5) for c in range(6)})
    starts = {f"v{i}": f"{r},0" for i, r in enumerate(range(5))}
    goals = {f"v{i}": [[Goal(f"{4 - r},5")], [Goal(f"{r},1")]] for i, r in enumerate(range(5))}
    config = SimConfig(delay_probability=0.3, delay_range=(1.0, 8.0), partial=True)
    stats, tasks = simulate(layout, starts, goals, until=2000.0, config=config)
    assert sum(tasks.done.values()) == 10
    assert stats.collisions == 0
    assert stats.wait_cycles == 0


def test_weighted_search_stays_within_its_bound() -> None:
    layout = Layout.grid({(r, c) for r in range(8) for c in range(12)})
    exact = manager(layout, {"a": "0,0", "b": "7,11"})
    loose = manager(layout, {"a": "0,0", "b": "7,11"}, weight=1.5)
    for m in (exact, loose):
        m.plan("b", "0,11", 0.0)
    best = exact.plan("a", "7,11", 0.0).arrive[-1]
    assert best <= loose.plan("a", "7,11", 0.0).arrive[-1] <= 1.5 * best


def test_amr_class_turns_a_quarter_in_a_second() -> None:
    assert AMR.rotation_speed == pytest.approx(math.pi / 2)
