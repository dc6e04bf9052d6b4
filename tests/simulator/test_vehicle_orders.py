"""VirtualVehicle order handling: driving, node states, updates, rejections (no MQTT)."""

from __future__ import annotations

import math

import pytest

from tests.simulator.builders import (
    action,
    error_types,
    finished,
    make_order,
    make_vehicle,
    node,
    run,
    run_until,
    status,
)
from vda5050 import Action, Order
from vda5050.enums import ActionStatus, BlockingType, ErrorLevel


def test_drives_order_to_completion() -> None:
    vehicle = make_vehicle()
    assert vehicle.on_order(make_order("o1", ["n1", "n2", "n3"]))
    first = vehicle.build_state()
    assert first.order_id == "o1"
    assert [n.node_id for n in first.node_states] == ["n1", "n2", "n3"]
    assert [e.edge_id for e in first.edge_states] == ["e-n1-n2", "e-n2-n3"]

    states = run_until(vehicle, finished)
    seen = [[n.node_id for n in s.node_states] for s in states]
    # nodeStates shrink node by node; the preceding edge goes with each node.
    assert seen[0] == ["n2", "n3"]
    assert ["n3"] in seen
    assert seen[-1] == []
    assert [e.edge_id for e in states[seen.index(["n3"])].edge_states] == ["e-n2-n3"]
    final = vehicle.build_state()
    assert (final.last_node_id, final.last_node_sequence_id) == ("n3", 4)
    assert final.agv_position is not None
    assert (final.agv_position.x, final.agv_position.y) == (10.0, 0.0)
    assert not final.driving
    assert final.distance_since_last_node == 0.0
    assert final.order_id == "o1"
    assert final.node_states == []
    assert final.edge_states == []


def test_pose_is_interpolated_along_the_edge() -> None:
    vehicle = make_vehicle(speed=1.0)
    vehicle.on_order(make_order("o1", ["n1", "n2", "n3", "n4"]))
    run(vehicle, 2.5)
    state = vehicle.build_state()
    assert state.agv_position is not None
    assert state.agv_position.x == pytest.approx(2.4, abs=0.11)
    assert state.agv_position.theta == pytest.approx(0.0)
    assert state.driving
    assert state.velocity is not None
    assert state.velocity.vx == 1.0
    assert state.distance_since_last_node == pytest.approx(2.4, abs=0.11)
    run_until(vehicle, lambda v: v.last_node_id == "n3")
    run(vehicle, 1.0)
    assert vehicle.theta == pytest.approx(math.pi / 2)  # heading up the n3→n4 edge


def test_first_node_is_traversed_immediately() -> None:
    vehicle = make_vehicle()
    vehicle.on_order(make_order("o1", ["n1", "n2"]))
    vehicle.tick(0.1)
    state = vehicle.build_state()
    assert (state.last_node_id, state.last_node_sequence_id) == ("n1", 0)
    assert [n.node_id for n in state.node_states] == ["n2"]


def test_edge_max_speed_caps_speed() -> None:
    vehicle = make_vehicle(speed=2.0)
    order = make_order("o1", ["n1", "n2"])
    order.edges[0].max_speed = 0.5
    vehicle.on_order(order)
    run(vehicle, 2.1)
    assert vehicle.x == pytest.approx(1.0, abs=0.06)


def test_stops_at_last_released_node_until_base_is_extended() -> None:
    vehicle = make_vehicle()
    vehicle.on_order(make_order("o1", ["n1", "n2", "n3", "n4"], released=2))
    run(vehicle, 30)
    state = vehicle.build_state()
    assert state.last_node_id == "n2"
    assert not state.driving
    assert [(n.node_id, n.released) for n in state.node_states] == [("n3", False), ("n4", False)]
    assert all(not e.released for e in state.edge_states)
    assert state.new_base_request is True

    update = make_order("o1", ["n2", "n3", "n4"], update_id=1, first_seq=2)
    assert vehicle.on_order(update)
    assert vehicle.build_state().order_update_id == 1
    run_until(vehicle, finished)
    assert (vehicle.last_node_id, vehicle.last_node_sequence_id) == ("n4", 6)


def test_update_while_driving_stitches_at_last_base_node() -> None:
    vehicle = make_vehicle()
    vehicle.on_order(make_order("o1", ["n1", "n2", "n3", "n4"], released=3))
    run(vehicle, 1.0)  # on the way to n2; last base node is n3 (seq 4)
    assert vehicle.on_order(make_order("o1", ["n3", "n4", "n5"], update_id=1, first_seq=4))
    state = vehicle.build_state()
    assert [(n.node_id, n.sequence_id) for n in state.node_states] == [
        ("n2", 2),
        ("n3", 4),
        ("n4", 6),
        ("n5", 8),
    ]
    run_until(vehicle, finished)
    assert vehicle.last_node_id == "n5"


def test_update_after_completion_stitches_at_last_node() -> None:
    vehicle = make_vehicle()
    vehicle.on_order(make_order("o1", ["n1", "n2", "n3"]))
    run_until(vehicle, finished)
    assert vehicle.on_order(make_order("o1", ["n3", "n4"], update_id=1, first_seq=4))
    run_until(vehicle, finished)
    assert (vehicle.last_node_id, vehicle.last_node_sequence_id) == ("n4", 6)


def test_update_replaces_horizon_and_its_actions() -> None:
    vehicle = make_vehicle()
    pick = action("pick", "horizon-pick")
    vehicle.on_order(make_order("o1", ["n1", "n2", "n3", "n4"], released=2, actions={"n4": [pick]}))
    assert status(vehicle, "horizon-pick") is ActionStatus.WAITING
    update = make_order("o1", ["n2", "n3"], update_id=1, first_seq=2, released=1)
    assert vehicle.on_order(update)
    state = vehicle.build_state()
    assert [(n.node_id, n.released) for n in state.node_states] == [
        ("n1", True),
        ("n2", True),
        ("n3", False),
    ]
    assert status(vehicle, "horizon-pick") is None


@pytest.mark.parametrize(
    ("update", "why"),
    [
        (make_order("o1", ["n1", "n2", "n3", "n4"], update_id=1), "restarts at the first node"),
        (make_order("o1", ["n2", "n3", "n4"], update_id=1, first_seq=4), "wrong sequenceId"),
        (make_order("o1", ["n3", "n4"], update_id=1, first_seq=4), "not the last base node"),
    ],
)
def test_update_not_stitching_is_rejected(update: Order, why: str) -> None:
    vehicle = make_vehicle()
    vehicle.on_order(make_order("o1", ["n1", "n2", "n3", "n4"], released=2))
    run(vehicle, 1.0)
    assert not vehicle.on_order(update), why
    state = vehicle.build_state()
    assert (state.order_id, state.order_update_id) == ("o1", 0)
    assert [e.error_type for e in state.errors] == ["orderUpdateError"]
    assert state.errors[0].error_level is ErrorLevel.WARNING
    run(vehicle, 10)
    assert vehicle.last_node_id == "n2"  # the old order continues


def test_lower_update_id_is_rejected_and_same_update_id_ignored() -> None:
    vehicle = make_vehicle()
    vehicle.on_order(make_order("o1", ["n1", "n2", "n3"], released=2, update_id=3))
    assert not vehicle.on_order(make_order("o1", ["n1", "n2", "n3"], update_id=3))
    assert error_types(vehicle) == []
    assert [n.released for n in vehicle.build_state().node_states] == [True, True, False]
    assert not vehicle.on_order(make_order("o1", ["n2", "n3"], update_id=2, first_seq=2))
    state = vehicle.build_state()
    assert state.order_update_id == 3
    assert [e.error_type for e in state.errors] == ["orderUpdateError"]
    refs = {r.reference_key: r.reference_value for r in state.errors[0].error_references or []}
    assert refs == {"orderId": "o1", "orderUpdateId": "2"}


def _bad(mutate: str) -> Order:
    order = make_order("bad", ["n1", "n2", "n3"])
    if mutate == "no nodes":
        order.nodes, order.edges = [], []
    elif mutate == "edge count":
        order.edges = order.edges[:1]
    elif mutate == "odd node sequence":
        order.nodes[1].sequence_id = 3
    elif mutate == "edge sequence gap":
        order.edges[1].sequence_id = 5
    elif mutate == "edge endpoints":
        order.edges[1].start_node_id = "n9"
    elif mutate == "released after horizon":
        order.nodes[1].released = False
        order.edges[0].released = False
    elif mutate == "edge released without node":
        order.nodes[2].released = False
    elif mutate == "first node unreleased":
        for element in [*order.nodes, *order.edges]:
            element.released = False
    elif mutate == "start far away":
        order = make_order("bad", ["n9", "n3"])
        order.edges[0].start_node_id = "n9"
    elif mutate == "unknown map":
        order.nodes[2] = node(4, "n3", map_id="elsewhere")
    elif mutate == "new order not at sequence 0":
        order = make_order("bad", ["n1", "n2"], first_seq=2)
    return order


@pytest.mark.parametrize(
    "mutate",
    [
        "no nodes",
        "edge count",
        "odd node sequence",
        "edge sequence gap",
        "edge endpoints",
        "released after horizon",
        "first node unreleased",
        "start far away",
        "unknown map",
        "new order not at sequence 0",
    ],
)
def test_invalid_orders_raise_validation_error(mutate: str) -> None:
    vehicle = make_vehicle()
    assert not vehicle.on_order(_bad(mutate))
    state = vehicle.build_state()
    assert (state.order_id, state.order_update_id) == ("", 0)
    assert [(e.error_type, e.error_level) for e in state.errors] == [
        ("validationError", ErrorLevel.WARNING)
    ]
    assert state.node_states == []


def test_edge_released_without_its_end_node_is_invalid() -> None:
    vehicle = make_vehicle()
    assert not vehicle.on_order(_bad("edge released without node"))
    assert error_types(vehicle) == ["validationError"]


def test_start_within_reach_or_on_last_node_is_accepted() -> None:
    vehicle = make_vehicle()
    near = make_order("o1", ["n1", "n2"])
    near.nodes[0] = node(0, "other", xy=(0.3, 0.2))
    near.edges[0].start_node_id = "other"
    assert vehicle.on_order(near)


@pytest.mark.parametrize(
    "actions",
    [
        [action("dance", "a1")],
        [action("pick", "a1", BlockingType.NONE)],  # pick is only SOFT/HARD
        [action("cancelOrder", "a1")],  # instant-only action on a node
        [action("initPosition", "a1", x=1.0)],  # required parameters missing
        [action("pick", "a1"), action("drop", "a1")],  # duplicate actionId
    ],
)
def test_unsupported_actions_raise_order_error(actions: list[Action]) -> None:
    vehicle = make_vehicle()
    assert not vehicle.on_order(make_order("o1", ["n1", "n2"], actions={"n2": actions}))
    assert error_types(vehicle) == ["orderError"]
    assert vehicle.order_id == ""


def test_edge_actions_are_rejected() -> None:
    vehicle = make_vehicle()
    order = make_order("o1", ["n1", "n2"])
    order.edges[0].actions = [action("pick", "a1")]
    assert not vehicle.on_order(order)
    assert error_types(vehicle) == ["orderError"]


def test_rejection_error_stays_until_next_accepted_order() -> None:
    vehicle = make_vehicle()
    vehicle.on_order(_bad("edge count"))
    run(vehicle, 5)
    assert error_types(vehicle) == ["validationError"]
    assert vehicle.on_order(make_order("good", ["n1", "n2"]))
    assert error_types(vehicle) == []


def test_new_order_while_busy_is_rejected() -> None:
    vehicle = make_vehicle()
    vehicle.on_order(make_order("o1", ["n1", "n2", "n3"]))
    run(vehicle, 1.0)
    assert not vehicle.on_order(make_order("o2", ["n1", "n2"]))
    assert vehicle.order_id == "o1"
    assert error_types(vehicle) == ["orderError"]
    run_until(vehicle, finished)
    assert vehicle.last_node_id == "n3"


def test_pending_horizon_means_not_idle() -> None:
    vehicle = make_vehicle()
    vehicle.on_order(make_order("o1", ["n1", "n2", "n3"], released=2))
    run(vehicle, 10)
    assert not vehicle.on_order(make_order("o2", ["n2", "n3"]))
    assert vehicle.order_id == "o1"


def test_new_order_after_completion_resets_action_states() -> None:
    vehicle = make_vehicle()
    vehicle.on_order(make_order("o1", ["n1", "n2"], actions={"n2": [action("pick", "p1")]}))
    run_until(vehicle, finished)
    assert status(vehicle, "p1") is ActionStatus.FINISHED
    assert vehicle.on_order(make_order("o2", ["n2", "n3"], actions={"n3": [action("drop", "d1")]}))
    state = vehicle.build_state()
    assert [a.action_id for a in state.action_states] == ["d1"]
    assert state.order_id == "o2"
    assert state.order_update_id == 0
    run_until(vehicle, finished)
    assert vehicle.build_state().loads == []


def test_node_position_missing_falls_back_to_layout() -> None:
    vehicle = make_vehicle()
    order = make_order("o1", ["n1", "n2"])
    order.nodes[1].node_position = None
    assert vehicle.on_order(order)
    run_until(vehicle, finished)
    assert (vehicle.x, vehicle.y) == (5.0, 0.0)
    unknown = make_order("o2", ["n2", "n3"])
    unknown.nodes[1].node_id = "nowhere"
    unknown.nodes[1].node_position = None
    unknown.edges[0].end_node_id = "nowhere"
    assert not vehicle.on_order(unknown)
    assert error_types(vehicle) == ["validationError"]
