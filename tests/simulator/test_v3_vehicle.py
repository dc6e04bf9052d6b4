"""A virtual vehicle speaking 3.0: orders and instant actions through the 3.0 message edge."""

from __future__ import annotations

import pytest

from simulator import wire
from simulator.execution import INSTANT_STATES_FULL, INSTANT_STATES_MAX
from simulator.vehicle import VirtualVehicle
from tests.simulator.builders import (
    action,
    error_types,
    finished,
    instant3,
    make_order,
    make_order3,
    make_vehicle,
    node,
    run3,
    run3_until,
    send3,
    status,
)
from vda5050 import DecodeError, Order, TopicKind, encode, v3
from vda5050.adapt import order_v2_to_v3
from vda5050.enums import ActionStatus, BlockingType, OperatingMode

V3 = "3.0.0"


def _vehicle(**config: object) -> VirtualVehicle:
    return make_vehicle(version=V3, **config)


def _state(vehicle: VirtualVehicle) -> v3.State:
    (state,) = wire.states(vehicle)
    assert isinstance(state, v3.State)
    return state


def test_order_is_driven_to_completion_in_3_0() -> None:
    vehicle = _vehicle()
    pick = action("pick", "p1", BlockingType.HARD, loadId="L1", loadType="EPAL")
    look = action("detectObject", "d1", BlockingType.NONE, objectType="pallet")
    order = make_order3("o1", ["n1", "n2", "n3"], actions={"n2": [pick], "n3": [look]})
    assert order.order_update_id == 0
    assert send3(vehicle, order)
    first = _state(vehicle)
    assert first.version == V3
    assert first.timestamp.endswith("Z")
    assert len(first.timestamp.rsplit(".", 1)[1]) == 4  # .fffZ
    assert (first.order_id, first.order_update_id) == ("o1", 0)
    # 3.0: the first node (standing on it) is never in nodeStates.
    assert [n.node_id for n in first.node_states] == ["n2", "n3"]
    assert [e.edge_id for e in first.edge_states] == ["e-n1-n2", "e-n2-n3"]
    assert [a.action_id for a in first.action_states] == ["p1", "d1"]
    assert first.instant_action_states == []

    states = run3_until(vehicle, finished)
    assert all(not any(n.sequence_id == 0 for n in s.node_states) for s in states)
    final = _state(vehicle)
    assert final.node_states == []
    assert final.edge_states == []
    assert (final.last_node_id, final.last_node_sequence_id) == ("n3", 4)
    assert [(a.action_id, a.action_status) for a in final.action_states] == [
        ("p1", v3.ActionStatus.FINISHED),
        ("d1", v3.ActionStatus.FINISHED),
    ]
    assert final.loads is not None
    assert final.loads[0].load_id == "L1"
    assert final.mobile_robot_position is not None
    assert final.mobile_robot_position.localized
    assert final.power_supply.state_of_charge < 100.0
    assert final.operating_mode is v3.OperatingMode.AUTOMATIC
    assert final.errors == []


def test_new_order_needs_order_update_id_0() -> None:
    vehicle = _vehicle()
    assert not send3(vehicle, make_order3("o1", ["n1", "n2"], update_id=1))
    assert error_types(vehicle) == ["VALIDATION_FAILURE"]
    assert send3(vehicle, make_order3("o1", ["n1", "n2"]))
    assert error_types(vehicle) == []
    # 2.x vehicles accept any orderUpdateId for a new order.
    legacy = make_vehicle()
    assert legacy.on_order(make_order("o1", ["n1", "n2"], update_id=1))


def test_same_order_update_id_resend_must_be_identical() -> None:
    vehicle = _vehicle()
    order = make_order3("o1", ["n1", "n2", "n3"], released=2)
    assert send3(vehicle, order)
    order.header_id += 1  # a resend differs only in the header: ignored
    assert not send3(vehicle, order)
    assert error_types(vehicle) == []
    changed = make_order3("o1", ["n1", "n2", "n4"], released=2)
    assert not send3(vehicle, changed)
    assert error_types(vehicle) == ["SAME_ORDER_UPDATE_ID"]


def test_rejections_use_3_0_error_types() -> None:
    vehicle = _vehicle()
    assert send3(vehicle, make_order3("o1", ["n1", "n2", "n3"], released=2, update_id=0))
    busy = make_order3("o2", ["n1", "n2"])
    assert not send3(vehicle, busy)
    assert error_types(vehicle) == ["OTHER_ORDER_ACTIVE"]
    older = make_order3("o1", ["n2", "n3"], first_seq=2, update_id=0)
    older.order_update_id = 0
    vehicle.order_update_id = 2  # pretend update 2 was accepted
    assert not send3(vehicle, older)
    assert error_types(vehicle)[-1] == "OUTDATED_ORDER_UPDATE"
    bad_stitch = make_order3("o1", ["n3", "n4"], first_seq=4, update_id=3)
    assert not send3(vehicle, bad_stitch)
    assert error_types(vehicle)[-1] == "VALIDATION_FAILURE"
    errors = _state(vehicle).errors
    assert {e.error_level for e in errors} == {v3.ErrorLevel.WARNING}
    refs = {(r.reference_key, r.reference_value) for r in errors[-1].error_references or []}
    assert ("orderUpdateId", "3") in refs


def test_validation_rejections() -> None:
    cases = {
        "UNKNOWN_MAP_ID": make_order("o1", ["n1", "n2"]),
        "START_NODE_OUT_OF_RANGE": make_order("o1", ["n9", "n2"]),
        "INVALID_ORDER_ACTION": make_order("o1", ["n1", "n2"], actions={"n2": [action("x", "a")]}),
        "VALIDATION_FAILURE": make_order("o1", ["n1", "n2"], first_seq=2),
    }
    cases["UNKNOWN_MAP_ID"].nodes[1] = node(2, "n2", map_id="elsewhere")
    for expected, order in cases.items():
        vehicle = _vehicle()
        order.timestamp = "2024-01-01T00:00:00.000Z"
        assert not send3(vehicle, _as_v3(order)), expected
        assert error_types(vehicle) == [expected]


def _as_v3(order: Order) -> v3.Order:
    return order_v2_to_v3(order, version=V3)


def test_mode_and_cancel_rules() -> None:
    vehicle = _vehicle()
    vehicle.set_operating_mode(OperatingMode.SERVICE)
    assert not send3(vehicle, make_order3("o1", ["n1", "n2"]))
    assert error_types(vehicle) == ["MOBILE_ROBOT_NOT_AVAILABLE"]
    vehicle.set_operating_mode(OperatingMode.AUTOMATIC)
    assert send3(vehicle, make_order3("o1", ["n1", "n2", "n3"]))
    run3(vehicle, 1.0)
    # cancelOrder naming another order fails with NO_ORDER_TO_CANCEL and changes nothing.
    send3(vehicle, instant3(action("cancelOrder", "c1", BlockingType.NONE, orderId="o9")))
    assert status(vehicle, "c1") is ActionStatus.FAILED
    assert error_types(vehicle) == ["NO_ORDER_TO_CANCEL"]
    assert vehicle.pending
    send3(vehicle, instant3(action("cancelOrder", "c2", BlockingType.NONE, orderId="o1")))
    run3_until(vehicle, lambda v: status(v, "c2") is ActionStatus.FINISHED)
    update = make_order3("o1", [vehicle.last_node_id, "n3"], first_seq=2, update_id=1)
    assert not send3(vehicle, update)
    assert error_types(vehicle)[-1] == "ORDER_UPDATE_FOLLOWING_CANCEL"


def test_instant_action_states_are_separate_and_kept_until_cleared() -> None:
    vehicle = _vehicle()
    send3(vehicle, instant3(action("stateRequest", "s1"), action("startPause", "p1")))
    state = _state(vehicle)
    assert [a.action_id for a in state.instant_action_states] == ["s1", "p1"]
    assert state.action_states == []
    send3(vehicle, instant3(action("stopPause", "p2")))
    assert send3(vehicle, make_order3("o1", ["n1", "n2"]))
    run3_until(vehicle, finished)
    assert send3(vehicle, make_order3("o2", ["n2", "n3"]))  # a new order keeps them (3.0)
    state = _state(vehicle)
    assert [a.action_id for a in state.instant_action_states] == ["s1", "p1", "p2"]
    send3(vehicle, instant3(action("clearInstantActions", "clr")))
    state = _state(vehicle)
    assert [(a.action_id, a.action_status) for a in state.instant_action_states] == [
        ("clr", v3.ActionStatus.FINISHED)
    ]


def test_invalid_instant_actions() -> None:
    vehicle = _vehicle()
    # The decoder accepts a SOFT instant action so the vehicle can refuse it properly.
    soft = instant3(action("stateRequest", "s1"))
    soft.actions[0].blocking_type = v3.BlockingType.SOFT
    send3(vehicle, soft)
    send3(vehicle, instant3(action("dance", "d1")))
    assert status(vehicle, "s1") is ActionStatus.FAILED
    assert status(vehicle, "d1") is ActionStatus.FAILED
    assert error_types(vehicle) == ["INVALID_INSTANT_ACTION", "INVALID_INSTANT_ACTION"]


def test_initialize_position_keeps_its_3_0_name() -> None:
    vehicle = _vehicle()
    init = action("initPosition", "i1", x=5.0, y=0.0, theta=0.0, mapId="demo", lastNodeId="n2")
    message = instant3(init)
    assert message.actions[0].action_type == "initializePosition"
    send3(vehicle, message)
    assert vehicle.last_node_id == "n2"
    reported = _state(vehicle).instant_action_states[0]
    assert (reported.action_type, reported.action_status) == (
        "initializePosition",
        v3.ActionStatus.FINISHED,
    )


def test_single_runs_alone_while_driving() -> None:
    vehicle = _vehicle()
    single = action("detectObject", "d1", BlockingType.NONE)
    after = action("detectObject", "d2", BlockingType.NONE)
    order = make_order3("o1", ["n1", "n2", "n3"], actions={"n2": [single, after]})
    order.nodes[1].actions[0].blocking_type = v3.BlockingType.SINGLE
    assert send3(vehicle, order)
    run3_until(vehicle, lambda v: status(v, "d1") is ActionStatus.RUNNING)
    assert status(vehicle, "d2") is ActionStatus.WAITING  # not in parallel with SINGLE
    run3(vehicle, 0.3)
    assert vehicle.driving  # SINGLE lets the vehicle drive on
    run3_until(vehicle, lambda v: status(v, "d2") is ActionStatus.RUNNING)
    assert status(vehicle, "d1") is ActionStatus.FINISHED


def test_3_0_only_actions_are_refused_by_2_x_vehicles() -> None:
    legacy = make_vehicle()
    order = make_order("o1", ["n1", "n2"], actions={"n2": [action("detectObject", "d1")]})
    assert not legacy.on_order(order)
    assert error_types(legacy) == ["orderError"]


def test_a_2_x_order_does_not_decode_for_a_3_0_vehicle() -> None:
    vehicle = _vehicle()
    legacy = make_order("o1", ["n1", "n2"])
    position = legacy.nodes[0].node_position
    assert position is not None
    position.allowed_deviation_xy = 0.5  # a number in 2.x, an ellipse in 3.0
    with pytest.raises(DecodeError) as info:
        wire.decode_inbound(TopicKind.ORDER, encode(legacy), V3)
    vehicle.reject_undecodable(str(info.value))
    assert error_types(vehicle) == ["VALIDATION_FAILURE"]
    with pytest.raises(DecodeError, match="only reads"):
        wire.decode_inbound(TopicKind.STATE, encode(_state(vehicle)), V3)


def test_long_instant_action_states_are_reported_and_bounded() -> None:
    vehicle = _vehicle()
    for i in range(INSTANT_STATES_FULL - 1):
        send3(vehicle, instant3(action("stateRequest", f"s{i}")))
    assert "INSTANT_ACTION_STATES_FULL" not in [e.error_type for e in _state(vehicle).errors]
    send3(vehicle, instant3(action("stateRequest", "one-more")))
    full = [e for e in _state(vehicle).errors if e.error_type == "INSTANT_ACTION_STATES_FULL"]
    assert [e.error_level for e in full] == [v3.ErrorLevel.URGENT]
    for i in range(INSTANT_STATES_MAX):
        send3(vehicle, instant3(action("stateRequest", f"t{i}")))
    kept = _state(vehicle).instant_action_states
    assert len(kept) == INSTANT_STATES_MAX
    assert kept[-1].action_id == f"t{INSTANT_STATES_MAX - 1}"  # the oldest went first
    send3(vehicle, instant3(action("clearInstantActions", "clr")))
    assert [e.error_type for e in _state(vehicle).errors] == []
