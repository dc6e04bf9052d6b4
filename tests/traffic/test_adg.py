"""ADG execution: base release, waiting, re-timing, re-planning, parking, static obstacles."""

import pytest

from tests.traffic.helpers import manager
from tests.traffic.test_sipp import overlaps
from traffic.layout import Layout
from traffic.manager import NoPlanError, TrafficManager
from traffic.plans import Goal, ReleasePolicy

LANE = Layout.grid([(0, c) for c in range(7)] + [(1, 3)], parking=[(1, 3)])


def released_conflicts(m: TrafficManager) -> list[tuple[int, int]]:
    """Pairs of vehicles holding (released, uncleared) conflicting resources at once."""
    found = []
    for queue in m.table.blocked:
        released = [h for h in queue if h.released]
        for a in released:
            for b in released:
                if a.vehicle < b.vehicle and m.conflicts.conflict(0, a.resource, b.resource):
                    found.append((a.vehicle, b.vehicle))
    return found


def waiting_pair() -> TrafficManager:
    """a drives the lane east; b, on the siding, waits to drive it west behind a."""
    m = manager(LANE, {"a": "0,0", "b": "1,3"}, policy=ReleasePolicy(max_steps=8))
    m.plan("a", "0,6", 0.0)
    m.plan("b", "0,0", 0.0)
    return m


def test_the_base_stops_where_another_vehicle_comes_first() -> None:
    m = waiting_pair()
    assert m.release_of("a").base_end == 6
    assert m.release_of("b").base_end == 0
    assert m.waiting_for("b") == ["a"]
    assert m.waiting_for("a") == []
    assert released_conflicts(m) == []


def test_progress_clears_and_releases_the_waiting_vehicle() -> None:
    m = waiting_pair()
    assert m.on_progress("a", 3, 3.0) == []  # a stands on 0,3: b still may not enter
    releases = m.on_progress("a", 4, 4.0)  # a's footprint has left 0,3
    assert [(r.vehicle_id, r.base_end, r.route_end) for r in releases] == [("b", 4, 4)]
    assert m.waiting_for("b") == []
    assert released_conflicts(m) == []


def test_progress_is_idempotent_and_never_beyond_the_base() -> None:
    m = waiting_pair()
    assert m.on_progress("a", 2, 2.0) == []
    assert m.on_progress("a", 2, 2.5) == []
    with pytest.raises(ValueError, match="beyond its base"):
        m.on_progress("b", 1, 3.0)


def test_the_base_is_capped_by_the_policy_but_always_at_least_one_step() -> None:
    m = manager(LANE, {"a": "0,0"}, policy=ReleasePolicy(max_steps=2, max_distance=0.5))
    plan = m.plan("a", "0,6", 0.0)
    assert plan.base_end == 1  # 0.5 m cap, but one step always goes
    m2 = manager(LANE, {"a": "0,0"}, policy=ReleasePolicy(max_steps=2, max_distance=9.0))
    assert m2.plan("a", "0,6", 0.0).base_end == 2
    releases = m2.on_progress("a", 1, 1.0)
    assert [r.base_end for r in releases] == [3]


def test_a_new_order_starts_a_new_route_from_where_the_vehicle_stands() -> None:
    m = manager(LANE, {"a": "0,0"})
    first = m.plan("a", "0,2", 0.0)
    m.on_progress("a", 1, 1.0)
    m.on_progress("a", 2, 2.0)
    second = m.plan("a", [Goal("0,5", 5.0)], 2.0)
    assert second.plan_id == first.plan_id + 1
    assert second.nodes[0] == "0,2"
    assert second.first_index == 0


def test_replanning_keeps_the_released_base() -> None:
    m = manager(LANE, {"a": "0,0"}, policy=ReleasePolicy(max_steps=2, max_distance=9.0))
    m.plan("a", "0,6", 0.0)
    m.on_progress("a", 1, 5.0)  # four seconds late
    plan = m.replan("a", 5.0)
    assert plan is not None
    assert plan.nodes[:4] == ("0,0", "0,1", "0,2", "0,3")
    assert plan.first_index == 3
    assert plan.arrive[4] >= 5.0 + 2.0


def test_retiming_pushes_a_late_vehicle_and_whoever_is_queued_behind_it() -> None:
    m = waiting_pair()
    b_before = m.vehicle("b").depart[0]
    m.tick(20.0)  # a reported nothing for 20 s: it is still short of 0,1
    a = m.vehicle("a")
    assert a.arrive[1] >= 20.0 - 2.0
    assert m.vehicle("b").depart[0] > b_before + 15.0
    assert overlaps(m) == []


def test_an_idle_vehicle_parks_off_the_lane() -> None:
    m = manager(LANE, {"a": "0,2"})
    plan = m.park("a", 0.0)
    assert plan.nodes[-1] == "1,3"
    for i in range(1, len(plan.nodes)):
        m.on_progress("a", i, float(i))
    again = m.park("a", 10.0)  # already parked: nothing new
    assert again.plan_id == plan.plan_id
    assert again.nodes[-1] == "1,3"
    other = manager(Layout.grid([(0, 0), (0, 1)]), {"a": "0,0"})
    with pytest.raises(NoPlanError):
        other.park("a", 0.0)  # no parking nodes at all


def test_a_blocked_vehicle_is_a_static_obstacle_others_plan_around() -> None:
    ring = Layout.grid({(r, c) for r in range(3) for c in range(5)} - {(1, 1), (1, 2), (1, 3)})
    m = manager(ring, {"a": "0,1", "b": "0,0"})
    m.plan("b", "0,4", 0.0)
    assert "0,1" not in m.plan_of("b").nodes or m.waiting_for("b") == ["a"]
    m.plan("a", "0,3", 0.0)
    replanned = m.block("a", 1.0)
    assert m.vehicle("a").static
    assert set(replanned) <= {"b"}
    assert "0,2" not in m.plan_of("b").nodes[m.plan_of("b").first_index :]
    assert overlaps(m) == []
    with pytest.raises(NoPlanError):
        m.plan("a", "0,4", 2.0)
    m.restore("a", "0,1", 3.0)
    assert not m.vehicle("a").static
    assert m.plan("a", "2,1", 3.0).nodes[0] == "0,1"


def test_no_wait_cycles_in_a_busy_queue() -> None:
    m = waiting_pair()
    assert m.wait_cycles() == []
    assert m.wait_for_graph()["b"] == ["a"]


def test_no_progress_check_blames_only_chains_that_stand_still() -> None:
    m = waiting_pair()
    assert m.stalled(30.0, after=60.0) == []
    assert set(m.stalled(100.0, after=60.0)) == {"a", "b"}  # a never reported a node
    m.on_progress("a", 1, 99.0)
    assert m.stalled(100.0, after=60.0) == []  # b waits, but a is driving


def test_vehicles_must_be_new_and_stand_on_free_nodes() -> None:
    m = manager(LANE, {"a": "0,0"})
    with pytest.raises(ValueError, match="already known"):
        m.add_vehicle("a", "0,1", 0.0)
    with pytest.raises(ValueError, match="reserved"):
        m.add_vehicle("b", "0,0", 0.0)
    with pytest.raises(ValueError, match="single goal"):
        m.plan("a", [Goal("0,1"), Goal("0,2")], 0.0, partial=True)


def test_the_cycle_check_finds_a_wait_for_cycle() -> None:
    from traffic.timing import find_cycles

    assert find_cycles({"a": ["b"], "b": ["c"], "c": []}) == []
    assert find_cycles({"a": ["b"], "b": ["c"], "c": ["a"]}) == [["a", "b", "c"]]
