"""Dual-version adapters: what master control publishes becomes valid 3.0, what a 3.0 robot
sends becomes valid 2.x Structs, and the documented mapping choices hold."""

from __future__ import annotations

import json
import re
from collections.abc import Callable
from typing import Any

import pytest

from vda5050 import (
    ActionStatus,
    BlockingType,
    ConnectionState,
    ErrorLevel,
    EStop,
    NodePosition,
    OperatingMode,
    TopicKind,
    decode,
    encode,
    make_action,
    v2,
    v3,
)
from vda5050.adapt import (
    connection_v2_to_v3,
    connection_v3_to_v2,
    error_level_v3,
    factsheet_v3_to_v2,
    instant_actions_v2_to_v3,
    is_retriable,
    order_v2_to_v3,
    state_v2_to_v3,
    state_v3_to_v2,
    visualization_v3_to_v2,
)
from vda5050.headers import HeaderCounter

from .samples import INSTANT_ACTION_FACTORIES, make_instant_actions, make_order, make_state
from .samples_v3 import (
    make_connection3,
    make_factsheet3,
    make_state3,
    make_state3_full,
    make_visualization3,
)
from .support import V3_SCHEMA, validator

TS_3 = re.compile(r"\d{4}-\d\d-\d\dT\d\d:\d\d:\d\d\.\d{3}Z")


def _errors(schema: str, kind: str, message: Any, *, strict: bool = False) -> list[str]:
    instance = json.loads(encode(message))
    found = validator(schema, kind, strict=strict).iter_errors(instance)
    return [f"{list(e.absolute_path)}: {e.message}" for e in found]


def _master_order(version: str) -> v2.Order:
    """An order shaped like control/order_messages.build_order output, header for 3.0."""
    header = HeaderCounter().header("Acme", "AGV-001", TopicKind.ORDER, version)
    route = ["n1", "n2", "n3"]
    nodes = [
        v2.Node(
            node_id=node,
            sequence_id=2 * i,
            released=i < 2,
            node_position=NodePosition(x=float(i), y=0.0, theta=None, map_id="hall-1"),
            actions=(
                [make_action("pick", {"stationType": "floor"}, BlockingType.HARD)] if i == 1 else []
            ),
        )
        for i, node in enumerate(route)
    ]
    edges = [
        v2.Edge(
            edge_id=f"{a}-{b}",
            sequence_id=2 * i + 1,
            released=i + 1 < 2,
            start_node_id=a,
            end_node_id=b,
            actions=[],
        )
        for i, (a, b) in enumerate(zip(route, route[1:], strict=False))
    ]
    return v2.Order(**header, order_id="o-1", order_update_id=0, nodes=nodes, edges=edges)


# --- master control → 3.0 robot --------------------------------------------------------------

_ORDERS: dict[str, Callable[[], v2.Order]] = {
    "sample-2.0": lambda: make_order("2.0.0"),
    "sample-2.1-corridor": lambda: make_order("2.1.0"),
    "control-shaped": lambda: _master_order("3.0.0"),
}


@pytest.mark.parametrize("strict", [False, True], ids=["official", "strict"])
@pytest.mark.parametrize("build", list(_ORDERS.values()), ids=list(_ORDERS))
def test_adapted_orders_validate_against_3_0(build: Callable[[], v2.Order], strict: bool) -> None:
    order = order_v2_to_v3(build(), version="3.0.0")
    assert _errors(V3_SCHEMA, "order", order, strict=strict) == []
    assert decode(TopicKind.ORDER, encode(order), version="3.0.0") == order


@pytest.mark.parametrize("strict", [False, True], ids=["official", "strict"])
@pytest.mark.parametrize("name", list(INSTANT_ACTION_FACTORIES))
def test_adapted_instant_actions_validate_against_3_0(name: str, strict: bool) -> None:
    action = INSTANT_ACTION_FACTORIES[name]()
    action.blocking_type = BlockingType.HARD  # 3.0 instant actions are NONE whatever we built
    message = instant_actions_v2_to_v3(make_instant_actions("2.0.0", [action]), version="3.0.0")
    assert _errors(V3_SCHEMA, "instantActions", message, strict=strict) == []
    assert message.actions[0].blocking_type is v3.BlockingType.NONE
    expected = "initializePosition" if name == "initPosition" else name
    assert message.actions[0].action_type == expected


def test_adapted_messages_keep_a_3_0_header() -> None:
    order = order_v2_to_v3(_master_order("3.0.0"))
    assert order.version == "3.0.0"
    assert TS_3.fullmatch(order.timestamp)
    assert order.header_id == 0
    assert order_v2_to_v3(make_order("2.0.0")).version == "2.0.0"  # copied unless overridden


def test_order_mapping() -> None:
    source = make_order("2.1.0")
    order = order_v2_to_v3(source, version="3.0.0")
    wire = json.loads(encode(order))
    assert "zoneSetId" not in wire
    assert "orderDescription" not in wire
    first = wire["nodes"][0]
    assert first["nodeDescriptor"] == "start"
    assert first["nodePosition"]["allowedDeviationXY"] == {"a": 0.5, "b": 0.5, "theta": 0.0}
    assert "mapDescription" not in first["nodePosition"]
    edge = wire["edges"][0]
    assert "startNodeId" not in edge
    assert "endNodeId" not in edge
    assert edge["edgeDescriptor"] == "aisle"
    assert (edge["maximumSpeed"], edge["maximumMobileRobotHeight"]) == (1.5, 2.2)
    assert edge["minimumLoadHandlingDeviceHeight"] == 0.1
    assert edge["reachOrientationBeforeEntering"] is True  # rotationAllowed was false
    assert edge["corridor"]["corridorReferencePoint"] == "KINEMATIC_CENTER"
    assert edge["trajectory"] == json.loads(encode(source.edges[0].trajectory))
    action = wire["nodes"][1]["actions"][0]
    assert action["actionDescriptor"] == "pick the pallet"
    assert action["blockingType"] == "HARD"
    assert "retriable" not in action


def test_will_and_connection_states_validate_in_3_0() -> None:
    counter = HeaderCounter()
    for state in ConnectionState:
        header = counter.header("Acme", "AGV-001", TopicKind.CONNECTION, "3.0.0")
        message = connection_v2_to_v3(v2.Connection(**header, connection_state=state))
        assert _errors(V3_SCHEMA, "connection", message, strict=True) == []
    broken = v2.Connection(**header, connection_state=ConnectionState.CONNECTIONBROKEN)
    assert connection_v2_to_v3(broken).connection_state is v3.ConnectionState.CONNECTION_BROKEN


# --- 3.0 robot → master control (one 2.x model) ---------------------------------------------


@pytest.mark.parametrize("build", [make_state3, make_state3_full], ids=["state", "full"])
def test_3_0_states_adapt_to_valid_2_x_structs(build: Callable[[], v3.State]) -> None:
    state = state_v3_to_v2(build())
    assert type(state) is v2.State
    assert _errors("2.1.0", "state", state, strict=True) == []
    assert decode(TopicKind.STATE, encode(state), version="2.1.0") == state


def test_3_0_factsheet_adapts_to_a_valid_2_x_factsheet() -> None:
    factsheet = factsheet_v3_to_v2(make_factsheet3())
    # Not strict: the 2.1 schema lacks angularSpeedMin/Max, which its document has (§7).
    assert _errors("2.1.0", "factsheet", factsheet) == []
    assert decode(TopicKind.FACTSHEET, encode(factsheet), version="2.1.0") == factsheet
    spec = factsheet.type_specification
    assert (spec.agv_kinematic, spec.agv_class) == ("DIFF", "CARRIER")
    assert spec.navigation_types == ["AUTONOMOUS"]
    limits = factsheet.protocol_limits
    assert limits.max_string_lens.id_len == 64
    assert limits.max_array_lens.order_nodes == 50
    assert limits.timing.min_order_interval == 0.5
    actions = {a.action_type: a for a in factsheet.protocol_features.agv_actions}
    assert set(actions) == {"initPosition", "detectObject"}  # 2.x action names
    assert actions["detectObject"].action_scopes == ["NODE"]  # ZONE left out
    assert actions["detectObject"].blocking_types == []  # SINGLE left out
    assert actions["initPosition"].result_description == "pose set"
    geometry = factsheet.agv_geometry
    assert geometry.envelopes2d is not None
    assert geometry.envelopes2d[0].set == "default"
    assert geometry.envelopes3d is not None
    assert geometry.envelopes3d[0].set == "hull"
    load_set = (factsheet.load_specification.load_sets or [])[0]
    assert (load_set.max_weight, load_set.agv_speed_limit) == (500.0, 1.0)
    assert factsheet.vehicle_config is not None
    assert factsheet.physical_parameters.height_min == 0.3


def test_3_0_visualization_and_connection_adapt_to_valid_2_x() -> None:
    visualization = visualization_v3_to_v2(make_visualization3())
    assert _errors("2.1.0", "visualization", visualization, strict=True) == []
    assert visualization.agv_position is not None
    assert visualization.agv_position.position_initialized is True
    for state in (v3.ConnectionState.ONLINE, v3.ConnectionState.CONNECTION_BROKEN):
        connection = connection_v3_to_v2(make_connection3(state))
        assert _errors("2.1.0", "connection", connection, strict=True) == []
    broken = connection_v3_to_v2(make_connection3(v3.ConnectionState.CONNECTION_BROKEN))
    assert broken.connection_state is ConnectionState.CONNECTIONBROKEN


def test_state_mapping() -> None:
    state = state_v3_to_v2(make_state3_full())
    assert state.version == "3.0.0"  # master control learns the robot speaks 3.0
    assert state.agv_position is not None
    assert state.agv_position.position_initialized
    assert state.battery_state.battery_charge == 76.5
    assert state.battery_state.reach == 12000.0
    assert state.safety_state.e_stop is EStop.NONE
    assert state.zone_set_id == "zones-a"
    assert state.maps is not None
    assert state.maps[1].map_description == "new racks"
    # Order actions first, then instant ones; zone actions are not order/instant actions.
    assert [a.action_id for a in state.action_states] == ["pick-1", "drop-1", "c0", "i0"]
    assert state.action_states[3].action_type == "initPosition"
    assert state.node_states[0].node_description == "pick station"
    assert state.edge_states[0].edge_description == "aisle"
    assert state.information is not None
    assert state.information[0].info_description == "heading to pick"


def test_retriable_is_not_terminal_and_can_be_told() -> None:
    state = state_v3_to_v2(make_state3())
    pick = state.action_states[0]
    assert pick.action_status is ActionStatus.PAUSED
    assert str(pick.action_status) not in {"FINISHED", "FAILED"}  # master: not done
    assert pick.result_description == "RETRIABLE: gripper blocked"
    assert is_retriable(pick)
    assert not is_retriable(state.action_states[1])
    bare = make_state3()
    bare.action_states[0].action_result = None
    assert state_v3_to_v2(bare).action_states[0].result_description == "RETRIABLE"


def test_error_levels() -> None:
    errors = state_v3_to_v2(make_state3()).errors
    levels = [(e.error_type, e.error_level) for e in errors]
    assert levels == [
        ("OUTDATED_ORDER_UPDATE", ErrorLevel.WARNING),
        ("INSTANT_ACTION_STATES_FULL", ErrorLevel.WARNING),  # URGENT: robot continues
        ("NODE_UNREACHABLE", ErrorLevel.FATAL),  # CRITICAL: order cannot go on
        ("LOCALIZATION_ERROR", ErrorLevel.FATAL),
    ]
    assert [error_level_v3(e) for e in errors] == ["WARNING", "URGENT", "CRITICAL", "FATAL"]
    assert errors[0].error_references is not None
    assert len(errors[0].error_references) == 2
    assert errors[3].error_references is None


@pytest.mark.parametrize(
    ("mode", "expected"),
    [
        (v3.OperatingMode.AUTOMATIC, OperatingMode.AUTOMATIC),
        (v3.OperatingMode.SEMIAUTOMATIC, OperatingMode.SEMIAUTOMATIC),
        (v3.OperatingMode.MANUAL, OperatingMode.MANUAL),
        (v3.OperatingMode.SERVICE, OperatingMode.SERVICE),
        (v3.OperatingMode.TEACH_IN, OperatingMode.TEACHIN),
    ],
)
def test_operating_modes_with_a_2_x_value(mode: v3.OperatingMode, expected: OperatingMode) -> None:
    assert state_v3_to_v2(make_state3(operating_mode=mode)).operating_mode is expected


@pytest.mark.parametrize("mode", [v3.OperatingMode.STARTUP, v3.OperatingMode.INTERVENED])
def test_3_0_only_modes_are_kept_as_strings(mode: v3.OperatingMode) -> None:
    state = state_v3_to_v2(make_state3(operating_mode=mode))
    assert str(state.operating_mode) == mode.value
    assert state.operating_mode not in {"AUTOMATIC", "SEMIAUTOMATIC"}  # master: unavailable
    assert json.loads(encode(state))["operatingMode"] == mode.value
    # Intended: such a Struct is not a valid 2.x message and must never be sent to a vehicle.
    assert _errors("2.1.0", "state", state)
    assert state_v2_to_v3(state).operating_mode is mode


def test_hibernating_is_kept_as_a_string() -> None:
    connection = connection_v3_to_v2(make_connection3(v3.ConnectionState.HIBERNATING))
    assert str(connection.connection_state) == "HIBERNATING"
    again = connection_v2_to_v3(connection)
    assert again.connection_state is v3.ConnectionState.HIBERNATING


def test_emergency_stops() -> None:
    for stop in v3.ActiveEmergencyStop:
        state = make_state3(
            safety_state=v3.SafetyState(active_emergency_stop=stop, field_violation=False)
        )
        assert state_v3_to_v2(state).safety_state.e_stop == stop.value
    legacy = make_state("2.0.0")
    legacy.safety_state = v2.SafetyState(e_stop=EStop.AUTOACK, field_violation=False)
    safety = state_v2_to_v3(legacy).safety_state
    assert safety == v3.SafetyState(
        active_emergency_stop=v3.ActiveEmergencyStop.NONE, field_violation=True
    )


def test_missing_knot_vector_becomes_clamped_uniform() -> None:
    state = make_state3()
    trajectory = state.edge_states[0].trajectory
    assert trajectory is not None
    trajectory.knot_vector = None
    trajectory.degree = None
    adapted = state_v3_to_v2(state).edge_states[0].trajectory
    assert adapted is not None
    assert adapted.degree == 1
    assert adapted.knot_vector == [0.0, 0.0, 0.5, 1.0, 1.0]  # 3 points, degree 1
    trajectory.degree = 3  # more than the control points allow: dropped
    assert state_v3_to_v2(state).edge_states[0].trajectory is None
