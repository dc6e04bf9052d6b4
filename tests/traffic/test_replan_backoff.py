"""The tick's re-plans of a vehicle that keeps finding the same route back off
(`TrafficManager(replan_backoff)`), and start afresh once it moves on."""

from tests.traffic.helpers import cells, manager
from traffic.layout import Layout
from traffic.manager import TrafficManager
from traffic.plans import ReleasePolicy

# one lane: b follows a, and no re-plan can find b another way
LANE = Layout.grid(cells(["........"]))
ONE_STEP = ReleasePolicy(max_steps=1, max_distance=1.0)


def _b_waits_behind_a(replan_backoff: int) -> TrafficManager:
    m = manager(LANE, {"a": "0,1", "b": "0,0"}, policy=ONE_STEP, replan_backoff=replan_backoff)
    m.plan("a", "0,7", 0.0)
    m.plan("b", "0,6", 0.0)
    return m


def _replans_over(m: TrafficManager, start: int, end: int) -> int:
    before = m.replans
    for second in range(start, end):
        m.tick(float(second))
    return m.replans - before


def test_re_plans_that_keep_the_route_back_off() -> None:
    plain, backing_off = _b_waits_behind_a(1), _b_waits_behind_a(8)
    assert plain.waiting_for("b") == ["a"] == backing_off.waiting_for("b")
    every_5_s = _replans_over(plain, 0, 120)
    assert every_5_s >= 20
    assert plain.replans_unchanged == plain.replans  # one lane: the same route each time
    # after 5 s waiting, then 10, 20, and every 40 s from then on
    assert _replans_over(backing_off, 0, 120) <= 6
    assert backing_off.replans_unchanged == backing_off.replans


def test_a_vehicle_that_moved_on_starts_afresh() -> None:
    m = _b_waits_behind_a(8)
    _replans_over(m, 0, 120)
    m.on_progress("a", 1, 120.0)  # a moves one node on and stops again
    m.on_progress("b", 1, 121.0)  # b follows and waits behind it once more
    assert m.waiting_for("b") == ["a"]
    assert _replans_over(m, 121, 141) == 2  # after 5 s waiting, then 10 s later
