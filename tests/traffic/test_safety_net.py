"""The safety net in `TrafficManager.tick`: a missed wake-up costs a waiting vehicle one tick."""

from tests.traffic.helpers import manager
from traffic.layout import Layout
from traffic.plans import ReleasePolicy


def test_tick_releases_a_vehicle_whose_wake_up_was_missed() -> None:
    lane = Layout.grid([(0, c) for c in range(7)] + [(1, 3)], parking=[(1, 3)])
    m = manager(lane, {"a": "0,0", "b": "1,3"}, policy=ReleasePolicy(max_steps=8))
    m.plan("a", "0,6", 0.0)
    m.plan("b", "0,0", 0.0)
    assert m.waiting_for("b") == ["a"]
    a = m.vehicle("a")
    for i in range(1, 5):  # a clears 0,0..0,3 behind the event path's back (no on_progress)
        edge = a.edge_holds[i]
        assert edge is not None
        m.table.remove(edge)
    for i in range(4):
        m.table.remove(a.node_holds[i])
    a.passed = 4
    assert m.release_of("b").base_end == 0  # nobody told b
    releases = m.tick(4.0)
    assert [(r.vehicle_id, r.base_end) for r in releases] == [("b", 4)]
    assert m.waiting_for("b") == []


def test_tick_keeps_a_vehicle_waiting_while_its_blocker_is_still_ahead() -> None:
    lane = Layout.grid([(0, c) for c in range(7)] + [(1, 3)], parking=[(1, 3)])
    m = manager(lane, {"a": "0,0", "b": "1,3"}, policy=ReleasePolicy(max_steps=8))
    m.plan("a", "0,6", 0.0)
    m.plan("b", "0,0", 0.0)
    m.on_progress("a", 3, 3.0)  # a stands on 0,3, where b would enter
    assert [r.vehicle_id for r in m.tick(3.5)] == []
    assert m.release_of("b").base_end == 0
    assert m.waiting_for("b") == ["a"]
    assert m.vehicle("b").blocked_since == 0.0  # the re-check does not restart the wait
