"""Adapter round trips, where the mapping is lossless (REFERENCE §6)."""

from __future__ import annotations

import msgspec
import pytest

from vda5050 import ConnectionState, v2, v3
from vda5050.adapt import (
    connection_v2_to_v3,
    connection_v3_to_v2,
    instant_actions_v2_to_v3,
    instant_actions_v3_to_v2,
    order_v2_to_v3,
    order_v3_to_v2,
    state_v2_to_v3,
    state_v3_to_v2,
    visualization_v2_to_v3,
    visualization_v3_to_v2,
)

from .samples import make_instant_actions, make_order, make_state, make_visualization
from .samples_v3 import (
    make_connection3,
    make_instant_actions3,
    make_order3,
    make_state3,
    make_visualization3,
)


def _lossless_v2_order(version: str) -> v2.Order:
    """A 2.x order without the fields 3.0 removed (zoneSetId, mapDescription)."""
    order = make_order(version)
    order.zone_set_id = None
    position = order.nodes[0].node_position
    assert position is not None
    position.map_description = None
    return order


def _lossless_v3_order() -> v3.Order:
    """A 3.0 order without 3.0-only content (retriable, SINGLE, ellipse, release fields)."""
    order = make_order3()
    order.order_description = None
    position = order.nodes[0].node_position
    assert position is not None
    position.allowed_deviation_xy = v3.AllowedDeviationXY(a=0.4, b=0.4, theta=0.0)
    for node in order.nodes:
        for action in node.actions:
            action.retriable = None
            action.blocking_type = v3.BlockingType.SOFT
    corridor = order.edges[0].corridor
    assert corridor is not None
    corridor.release_required = corridor.release_loss_behavior = None
    return order


@pytest.mark.parametrize("version", ["2.0.0", "2.1.0"])
def test_order_v2_v3_v2(version: str) -> None:
    order = _lossless_v2_order(version)
    assert order_v3_to_v2(order_v2_to_v3(order)) == order


def test_order_v3_v2_v3() -> None:
    order = _lossless_v3_order()
    assert order_v2_to_v3(order_v3_to_v2(order)) == order


def test_order_v3_to_v2_derives_edge_ends_and_keeps_3_0_values() -> None:
    order = order_v3_to_v2(make_order3())
    assert [(e.start_node_id, e.end_node_id) for e in order.edges] == [("n1", "n2"), ("n2", "n3")]
    assert order.edges[0].rotation_allowed is False
    position = order.nodes[0].node_position
    assert position is not None
    assert position.allowed_deviation_xy == 0.3  # the smaller semi-axis
    assert order.nodes[1].actions[0].blocking_type == "SINGLE"
    corridor = order.edges[0].corridor
    assert corridor is not None
    assert corridor.corridor_ref_point == "KINEMATICCENTER"
    # A malformed order (too many edges) still adapts; validation rejects it later.
    broken = make_order3()
    broken.edges.append(v3.Edge(edge_id="e9", sequence_id=5, released=False, actions=[]))
    assert order_v3_to_v2(broken).edges[-1].end_node_id == ""


def test_instant_actions_round_trips() -> None:
    legacy = make_instant_actions("2.0.0")
    assert instant_actions_v3_to_v2(instant_actions_v2_to_v3(legacy)) == legacy
    current = make_instant_actions3()
    assert instant_actions_v2_to_v3(instant_actions_v3_to_v2(current)) == current
    assert instant_actions_v3_to_v2(current).actions[1].action_type == "initPosition"


def _lossless_v3_state() -> v3.State:
    """make_state3 without the one field 2.x cannot hold (batteryCurrent)."""
    state = make_state3()
    state.power_supply.battery_current = None
    return state


def test_state_v3_v2_v3() -> None:
    state = _lossless_v3_state()
    instant = {a.action_id for a in state.instant_action_states}
    assert state_v2_to_v3(state_v3_to_v2(state), instant_action_ids=instant) == state


@pytest.mark.parametrize(
    "mode", [m for m in v3.OperatingMode], ids=[m.value for m in v3.OperatingMode]
)
def test_state_v3_v2_v3_every_mode_and_level(mode: v3.OperatingMode) -> None:
    state = _lossless_v3_state()
    state.operating_mode = mode
    instant = {a.action_id for a in state.instant_action_states}
    again = state_v2_to_v3(state_v3_to_v2(state), instant_action_ids=instant)
    assert again.operating_mode is mode
    assert [e.error_level for e in again.errors] == [e.error_level for e in state.errors]
    assert again.action_states[0].action_status is v3.ActionStatus.RETRIABLE
    assert again.action_states[0].action_result == "gripper blocked"


@pytest.mark.parametrize("version", ["2.0.0", "2.1.0"])
def test_state_v2_v3_v2(version: str) -> None:
    state = make_state(version)
    assert state.agv_position is not None
    state.agv_position.map_description = None  # dropped by 3.0
    assert state_v3_to_v2(state_v2_to_v3(state)) == state


def test_state_v2_to_v3_splits_instant_actions() -> None:
    state = make_state("2.1.0")
    ids = [a.action_id for a in state.action_states]
    adapted = state_v2_to_v3(state, instant_action_ids={ids[0]})
    assert [a.action_id for a in adapted.instant_action_states] == ids[:1]
    assert [a.action_id for a in adapted.action_states] == ids[1:]
    assert state_v2_to_v3(state).instant_action_states == []


@pytest.mark.parametrize("state", list(v3.ConnectionState))
def test_connection_round_trips(state: v3.ConnectionState) -> None:
    message = make_connection3(state)
    assert connection_v2_to_v3(connection_v3_to_v2(message)) == message


@pytest.mark.parametrize("state", list(ConnectionState))
def test_connection_v2_round_trips(state: ConnectionState) -> None:
    message = v2.Connection(
        header_id=1,
        timestamp="2024-03-11T11:40:03.12Z",
        version="2.0.0",
        manufacturer="Acme",
        serial_number="AGV-001",
        connection_state=state,
    )
    assert connection_v3_to_v2(connection_v2_to_v3(message)) == message


def test_visualization_round_trips() -> None:
    legacy = make_visualization("2.1.0")
    assert visualization_v3_to_v2(visualization_v2_to_v3(legacy)) == legacy
    current = msgspec.structs.replace(make_visualization3(), planned_path=None)
    current.intermediate_path = None
    back = visualization_v2_to_v3(
        visualization_v3_to_v2(current),
        reference_state_header_id=current.reference_state_header_id,
    )
    assert back == current
    with pytest.raises(ValueError, match="header"):
        visualization_v2_to_v3(v2.Visualization())
