"""VirtualVehicle actions, instant actions, pause, cancel, battery and time-lapse."""

from __future__ import annotations

import re

import pytest

from tests.simulator.builders import (
    action,
    error_types,
    finished,
    instant,
    make_order,
    make_vehicle,
    run,
    run_until,
    status,
)
from vda5050 import State
from vda5050.enums import ActionStatus, BlockingType, ErrorLevel, TopicKind

WAITING, INITIALIZING, RUNNING = (
    ActionStatus.WAITING,
    ActionStatus.INITIALIZING,
    ActionStatus.RUNNING,
)
FINISHED, FAILED = ActionStatus.FINISHED, ActionStatus.FAILED


def _history(states: list[State], action_id: str) -> list[ActionStatus]:
    """Distinct consecutive statuses of ``action_id`` across published states."""
    seen: list[ActionStatus] = []
    for state in states:
        for a in state.action_states:
            if a.action_id == action_id and (not seen or seen[-1] != a.action_status):
                seen.append(a.action_status)
    return seen


def test_pick_then_drop_sets_and_clears_loads() -> None:
    vehicle = make_vehicle()
    pick = action("pick", "p1", loadId="L-42", loadType="EPAL", stationType="rack")
    drop = action("drop", "d1", BlockingType.SOFT)
    vehicle.on_order(make_order("o1", ["n1", "n2", "n3"], actions={"n2": [pick], "n3": [drop]}))
    states = [vehicle.build_state()]
    states += run_until(vehicle, finished)
    assert _history(states, "p1") == [WAITING, INITIALIZING, RUNNING, FINISHED]
    assert _history(states, "d1") == [WAITING, INITIALIZING, RUNNING, FINISHED]
    loads = [[(ld.load_id, ld.load_type) for ld in s.loads or []] for s in states]
    assert [("L-42", "EPAL")] in loads
    assert loads[0] == []
    assert loads[-1] == []


def test_hard_action_blocks_driving_until_finished() -> None:
    vehicle = make_vehicle()
    vehicle.on_order(make_order("o1", ["n1", "n2", "n3"], actions={"n2": [action("pick", "p1")]}))
    run_until(vehicle, lambda v: v.last_node_id == "n2")
    run(vehicle, 1.5)  # pick lasts 2 s simulated (plus one tick per status change)
    assert (vehicle.x, vehicle.driving) == (5.0, False)
    assert status(vehicle, "p1") is RUNNING
    run_until(vehicle, lambda v: status(v, "p1") is FINISHED, max_seconds=3)
    run(vehicle, 1.0)
    assert vehicle.x > 5.0


def test_hard_actions_run_alone_soft_actions_in_parallel() -> None:
    vehicle = make_vehicle()
    node_actions = [
        action("startCharging", "c1", BlockingType.SOFT),
        action("pick", "p1", BlockingType.SOFT),
        action("drop", "d1", BlockingType.HARD),
    ]
    vehicle.on_order(make_order("o1", ["n1", "n2"], actions={"n2": node_actions}))
    run_until(vehicle, lambda v: status(v, "c1") is INITIALIZING)
    assert status(vehicle, "p1") is INITIALIZING  # SOFT + SOFT start together
    assert status(vehicle, "d1") is WAITING
    run_until(vehicle, lambda v: status(v, "d1") is not WAITING, max_seconds=5)
    assert status(vehicle, "c1") is FINISHED
    assert status(vehicle, "p1") is FINISHED
    run_until(vehicle, finished, max_seconds=5)
    assert status(vehicle, "d1") is FINISHED
    assert vehicle.loads == []


def test_drop_without_load_fails_and_order_still_completes() -> None:
    vehicle = make_vehicle()
    vehicle.on_order(make_order("o1", ["n1", "n2", "n3"], actions={"n2": [action("drop", "d1")]}))
    run_until(vehicle, finished)
    run_ = vehicle.actions.get("d1")
    assert run_ is not None
    assert run_.status is FAILED
    assert run_.result
    assert vehicle.last_node_id == "n3"


def test_pick_when_loaded_fails() -> None:
    vehicle = make_vehicle()
    picks = {"n2": [action("pick", "p1", loadId="A")], "n3": [action("pick", "p2")]}
    vehicle.on_order(make_order("o1", ["n1", "n2", "n3"], actions=picks))
    run_until(vehicle, finished)
    assert (status(vehicle, "p1"), status(vehicle, "p2")) == (FINISHED, FAILED)
    assert [ld.load_id for ld in vehicle.loads] == ["A"]


def test_cancel_without_order_fails_with_no_order_to_cancel() -> None:
    vehicle = make_vehicle()
    vehicle.on_instant_actions(instant(action("cancelOrder", "c1")))
    state = vehicle.build_state()
    assert [(a.action_id, a.action_status) for a in state.action_states] == [("c1", FAILED)]
    assert [(e.error_type, e.error_level) for e in state.errors] == [
        ("noOrderToCancel", ErrorLevel.WARNING)
    ]
    refs = state.errors[0].error_references or []
    assert [(r.reference_key, r.reference_value) for r in refs] == [("actionId", "c1")]


def test_cancel_while_driving_stops_at_next_node() -> None:
    vehicle = make_vehicle()
    order = make_order(
        "o1", ["n1", "n2", "n3", "n4"], actions={"n2": [action("pick", "p1")]}, released=3
    )
    vehicle.on_order(order)
    run(vehicle, 2.0)  # between n1 and n2
    vehicle.on_instant_actions(instant(action("cancelOrder", "c1", BlockingType.NONE)))
    state = vehicle.build_state()
    assert [n.node_id for n in state.node_states] == ["n2"]
    assert status(vehicle, "c1") is RUNNING
    assert status(vehicle, "p1") is FAILED  # WAITING actions fail
    run_until(vehicle, lambda v: status(v, "c1") is FINISHED, max_seconds=10)
    state = vehicle.build_state()
    assert state.node_states == []
    assert state.edge_states == []
    assert (state.order_id, state.last_node_id, state.last_node_sequence_id) == ("o1", "n2", 2)
    assert not state.driving
    run(vehicle, 5)
    assert vehicle.x == 5.0


def test_cancel_while_standing_is_immediate_and_blocks_updates() -> None:
    vehicle = make_vehicle()
    vehicle.on_order(make_order("o1", ["n1", "n2", "n3"], released=2))
    run(vehicle, 10)  # waiting at n2 for the base to be extended
    vehicle.on_instant_actions(instant(action("cancelOrder", "c1")))
    assert vehicle.build_state().node_states == []
    vehicle.tick(0.1)
    assert status(vehicle, "c1") is FINISHED
    # 2.x/3.0 (REFERENCE §3 D.21): after a cancel the master must use a new orderId.
    assert not vehicle.on_order(make_order("o1", ["n2", "n3"], update_id=1, first_seq=2))
    assert error_types(vehicle) == ["orderUpdateError"]
    assert vehicle.on_order(make_order("o2", ["n2", "n3"]))
    assert error_types(vehicle) == []
    run_until(vehicle, finished)
    assert vehicle.last_node_id == "n3"


def test_cancel_waits_for_running_action() -> None:
    vehicle = make_vehicle()
    vehicle.on_order(make_order("o1", ["n1", "n2", "n3"], actions={"n2": [action("pick", "p1")]}))
    run_until(vehicle, lambda v: status(v, "p1") is RUNNING)
    vehicle.on_instant_actions(instant(action("cancelOrder", "c1")))
    vehicle.tick(0.1)
    assert status(vehicle, "c1") is RUNNING
    run_until(vehicle, lambda v: status(v, "c1") is FINISHED, max_seconds=5)
    assert status(vehicle, "p1") is FINISHED
    assert vehicle.last_node_id == "n2"


def test_pause_and_resume() -> None:
    vehicle = make_vehicle()
    vehicle.on_order(make_order("o1", ["n1", "n2", "n3"]))
    run(vehicle, 1.0)
    vehicle.on_instant_actions(instant(action("startPause", "sp")))
    vehicle.tick(0.1)
    x = vehicle.x
    state = vehicle.build_state()
    assert state.paused is True
    assert not state.driving
    assert [a.action_status for a in state.action_states if a.action_id == "sp"] == [FINISHED]
    run(vehicle, 5)
    assert vehicle.x == x
    vehicle.on_instant_actions(instant(action("stopPause", "rp")))
    run(vehicle, 1.0)
    assert vehicle.x > x
    assert not vehicle.paused
    run_until(vehicle, finished)


def test_pause_freezes_actions() -> None:
    vehicle = make_vehicle()
    vehicle.on_order(make_order("o1", ["n1", "n2"], actions={"n2": [action("pick", "p1")]}))
    run_until(vehicle, lambda v: status(v, "p1") is RUNNING)
    vehicle.on_instant_actions(instant(action("startPause", "sp")))
    run(vehicle, 10)
    assert status(vehicle, "p1") is RUNNING
    vehicle.on_instant_actions(instant(action("stopPause", "rp")))
    run_until(vehicle, finished, max_seconds=5)


def test_battery_drains_while_driving_and_charges() -> None:
    vehicle = make_vehicle(battery_start=50.0)
    vehicle.on_order(make_order("o1", ["n1", "n2", "n3"]))
    run_until(vehicle, finished)  # 10 m ≈ 0.5 % plus idle drain
    assert 49.4 < vehicle.battery < 49.5
    vehicle.on_instant_actions(instant(action("startCharging", "c1")))
    assert vehicle.build_state().battery_state.charging is True
    run(vehicle, 10)
    assert vehicle.battery == pytest.approx(59.45, abs=0.2)
    run(vehicle, 60)
    assert vehicle.battery == 100.0
    vehicle.on_instant_actions(instant(action("stopCharging", "c2")))
    assert vehicle.build_state().battery_state.charging is False


def test_empty_battery_never_negative_and_stops_driving() -> None:
    vehicle = make_vehicle(battery_start=0.1)
    vehicle.on_order(make_order("o1", ["n1", "n2", "n3"]))
    run(vehicle, 20)
    assert vehicle.battery == 0.0
    assert 0 < vehicle.x < 5.0
    assert not vehicle.driving
    state = vehicle.build_state()
    assert ("batteryEmpty", ErrorLevel.FATAL) in [
        (e.error_type, e.error_level) for e in state.errors
    ]


def test_charging_node_action_and_driving_off_disconnects() -> None:
    vehicle = make_vehicle()
    charge = action("startCharging", "c1", BlockingType.HARD)
    vehicle.on_order(make_order("o1", ["n1", "n2"], actions={"n2": [charge]}))
    run_until(vehicle, finished)
    assert vehicle.charging
    assert vehicle.on_order(make_order("o2", ["n2", "n3"]))
    run(vehicle, 1.0)
    assert not vehicle.charging
    assert vehicle.driving


def test_time_lapse_scales_driving_actions_and_battery() -> None:
    vehicle = make_vehicle(time_scale=10.0)
    vehicle.on_order(make_order("o1", ["n1", "n2", "n3"], actions={"n2": [action("pick", "p1")]}))
    run(vehicle, 0.4)
    assert vehicle.sim_time == pytest.approx(4.0)  # 0.4 s wall = 4 s simulated
    assert vehicle.x == pytest.approx(4.0, abs=1.01)
    run_until(vehicle, finished, max_seconds=2.0)  # 10 m + 2 s pick in < 2 s wall
    assert vehicle.battery < 100.0 - 0.5


def test_instant_request_actions() -> None:
    vehicle = make_vehicle()
    vehicle.take_state_due()
    vehicle.take_factsheet_due()
    vehicle.on_instant_actions(instant(action("stateRequest", "s1")))
    assert vehicle.take_state_due()
    vehicle.on_instant_actions(instant(action("factsheetRequest", "f1")))
    assert vehicle.take_factsheet_due()
    vehicle.on_instant_actions(instant(action("selfDestruct", "x1")))
    statuses = {a.action_id: a.action_status for a in vehicle.build_state().action_states}
    assert statuses == {"s1": FINISHED, "f1": FINISHED, "x1": FAILED}


def test_init_position_only_when_idle() -> None:
    vehicle = make_vehicle()
    params = {"x": 10.0, "y": 5.0, "theta": 4.0, "mapId": "demo", "lastNodeId": "n4"}
    vehicle.on_instant_actions(instant(action("initPosition", "i1", **params)))
    state = vehicle.build_state()
    assert state.agv_position is not None
    assert (state.agv_position.x, state.agv_position.y) == (10.0, 5.0)
    assert -3.1416 <= state.agv_position.theta <= 3.1416  # normalised to [-pi, pi]
    assert (state.last_node_id, state.last_node_sequence_id) == ("n4", 0)
    vehicle.on_instant_actions(instant(action("initPosition", "i2", **{**params, "mapId": "x"})))
    assert status(vehicle, "i2") is FAILED
    vehicle.on_order(make_order("o1", ["n4", "n5"]))
    vehicle.on_instant_actions(instant(action("initPosition", "i3", **params)))
    assert status(vehicle, "i3") is FAILED


def test_header_ids_count_per_topic_and_timestamps_follow_version() -> None:
    vehicle = make_vehicle(version="2.1.0")
    assert [vehicle.build_state().header_id for _ in range(3)] == [0, 1, 2]
    assert vehicle.build_visualization().header_id == 0
    assert vehicle.build_factsheet().header_id == 0
    assert vehicle.headers.peek("sim", "AGV-1", TopicKind.STATE) == 3
    stamp = vehicle.build_state().timestamp
    assert re.fullmatch(r"\d{4}-\d\d-\d\dT\d\d:\d\d:\d\d\.\d\dZ", stamp)


def test_injected_errors_until_cleared() -> None:
    vehicle = make_vehicle()
    vehicle.inject_error("laserScannerDirty", ErrorLevel.FATAL, "clean me")
    assert error_types(vehicle) == ["laserScannerDirty"]
    vehicle.clear_injected_errors("other")
    assert error_types(vehicle) == ["laserScannerDirty"]
    vehicle.clear_injected_errors()
    assert error_types(vehicle) == []
