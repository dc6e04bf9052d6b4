"""A re-plan whose vehicle changed while its search let the lock go is searched again from
where the vehicle's route now ends.

Found in a 30-minute load run (docs/LOAD.md, ninth round): a vehicle waiting at its decision
point was re-planned by the tick; during the unlocked search the vehicle ahead moved on, which
released the waiting vehicle's next step (its base grew). The manager then searched again,
held, but from the old start, and committed that path after the new base: the route went from
a node to itself, and every later tick failed on it.
"""

from collections.abc import Iterator
from contextlib import contextmanager

import pytest

from tests.traffic.helpers import cells, manager
from traffic import speedups
from traffic.layout import Layout
from traffic.plans import ReleasePolicy

pytestmark = pytest.mark.skipif(
    speedups.COMPILED is None, reason="only the compiled search runs unlocked"
)

LANE = Layout.grid(cells(["......"]))
ONE_STEP = ReleasePolicy(max_steps=1, max_distance=1.0)


def test_a_re_plan_whose_vehicle_was_released_meanwhile_starts_from_its_new_base() -> None:
    m = manager(LANE, {"a": "0,0", "c": "0,1"}, policy=ONE_STEP)
    m.plan("c", "0,5", 0.0)
    m.plan("a", "0,4", 0.0)
    assert m.waiting_for("a") == ["c"]
    assert m.release_of("a").base_end == 0

    @contextmanager
    def meanwhile() -> Iterator[None]:
        yield  # a's path is found here; then c moves on, which releases a's next step
        m.unlocked = None
        m.on_progress("c", 1, 1.0)
        m.unlocked = meanwhile

    m.unlocked = meanwhile
    plan = m.replan("a", 1.0)

    assert plan is not None
    assert plan.nodes == ("0,0", "0,1", "0,2", "0,3", "0,4")  # no step from a node to itself
    assert m.release_of("a").base_end == 1
    assert (m.searches_repeated, m.searches_moved) == (1, 1)
    m.unlocked = None
    m.tick(2.0)  # the route is whole: re-timing walks it without a missing move


def test_a_failing_tick_does_not_stop_the_order_sync(monkeypatch: pytest.MonkeyPatch) -> None:
    from tests.traffic.test_link import Rig

    rig = Rig(("A", "W"))
    manager = rig.link.managers["m"]

    def broken(now: float, **options: object) -> list[object]:
        raise KeyError((119, 119))

    monkeypatch.setattr(manager, "tick", broken)
    rig.link.tick(10.0)  # logged and counted, not raised
    assert rig.link.problems == {"traffic tick failed on map m: KeyError((119, 119))": 1}


def test_a_re_plan_whose_vehicle_started_afresh_meanwhile_is_dropped() -> None:
    # a waits behind c; its tick re-plan searches unlocked, and meanwhile its order ends
    # (cancelled mid-route: control blocks and restores it where it stands). Searching again
    # with the old order's goals would give the idle vehicle a route nobody drives, its
    # released base held against everyone until its next order.
    m = manager(LANE, {"a": "0,0", "c": "0,1"}, policy=ONE_STEP)
    m.plan("c", "0,5", 0.0)
    m.plan("a", "0,4", 0.0)
    plan_id = m.vehicle("a").plan_id

    @contextmanager
    def meanwhile() -> Iterator[None]:
        yield
        m.unlocked = None
        m.block("a", 1.0)
        m.restore("a", "0,0", 1.0)
        m.unlocked = meanwhile

    m.unlocked = meanwhile
    assert m.replan("a", 1.0) is None

    a = m.vehicle("a")
    assert a.plan_id == plan_id + 1  # the restart, and no plan on top of it
    assert [m.layout.node_ids[n] for n in a.route] == ["0,0"]
    assert (a.base, a.passed) == (0, 0)
    assert m.searches_moved == 1
    m.unlocked = None
    assert m.plan("a", "0,3", 2.0).nodes[0] == "0,0"  # its next order starts where it stands
