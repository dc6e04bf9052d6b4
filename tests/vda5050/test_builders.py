"""Builders produce correct, schema-valid messages."""

from __future__ import annotations

import json
import re
import uuid

import pytest

from vda5050 import (
    ActionType,
    BlockingType,
    ConnectionState,
    TopicKind,
    action_params,
    cancel_order,
    decode,
    encode,
    factsheet_request,
    init_position,
    instant_action,
    make_action,
    make_connection,
    make_instant_actions,
    start_pause,
    state_request,
    stop_pause,
)

from .support import validator


def test_make_action_uses_uuid4_ids() -> None:
    first = make_action("beep")
    second = make_action("beep")
    assert uuid.UUID(first.action_id).version == 4
    assert first.action_id != second.action_id


def test_make_action_parameters_and_defaults() -> None:
    action = make_action("pick", {"stationType": "floor", "height": 0.5, "retries": 2})
    assert action.blocking_type is BlockingType.NONE
    assert action.action_parameters is not None
    assert [(p.key, p.value) for p in action.action_parameters] == [
        ("stationType", "floor"),
        ("height", 0.5),
        ("retries", 2),
    ]
    assert action_params(action) == {"stationType": "floor", "height": 0.5, "retries": 2}


@pytest.mark.parametrize("params", [None, {}])
def test_make_action_without_parameters_omits_the_field(params: dict[str, str] | None) -> None:
    wire = json.loads(encode(make_action("beep", params, BlockingType.SOFT, action_id="a1")))
    assert wire == {"actionType": "beep", "actionId": "a1", "blockingType": "SOFT"}


def test_make_action_description() -> None:
    action = make_action("beep", description="say hello")
    assert action.action_description == "say hello"


@pytest.mark.parametrize(
    ("factory", "action_type"),
    [
        (cancel_order, "cancelOrder"),
        (start_pause, "startPause"),
        (stop_pause, "stopPause"),
        (state_request, "stateRequest"),
        (factsheet_request, "factsheetRequest"),
    ],
)
def test_predefined_instant_actions(factory: object, action_type: str) -> None:
    action = factory()  # type: ignore[operator]
    assert action.action_type == action_type
    assert action.blocking_type is BlockingType.NONE
    assert action.action_parameters is None


def test_init_position_parameters() -> None:
    action = init_position(x=1.5, y=-2.0, theta=3.1, map_id="hall-1", last_node_id="n7")
    assert action.action_type == "initPosition"
    assert str(ActionType.INIT_POSITION) == "initPosition"
    assert action_params(action) == {
        "x": 1.5,
        "y": -2.0,
        "theta": 3.1,
        "mapId": "hall-1",
        "lastNodeId": "n7",
    }


@pytest.mark.parametrize("version", ["2.0.0", "2.1.0"])
def test_instant_action_message(version: str) -> None:
    message = instant_action(
        ActionType.START_PAUSE,
        header_id=5,
        manufacturer="Acme",
        serial_number="AGV-1",
        version=version,
    )
    assert message.header_id == 5
    assert message.version == version
    assert len(message.actions) == 1
    assert message.actions[0].action_type == "startPause"
    assert re.fullmatch(r"\d{4}-\d{2}-\d{2}T\d{2}:\d{2}:\d{2}\.\d{2}Z", message.timestamp)
    wire = json.loads(encode(message))
    assert list(validator(version, "instantActions", strict=True).iter_errors(wire)) == []
    assert decode(TopicKind.INSTANT_ACTIONS, encode(message), version=version) == message


def test_make_instant_actions_keeps_order_and_timestamp() -> None:
    actions = [cancel_order(), state_request()]
    message = make_instant_actions(
        actions,
        header_id=0,
        manufacturer="Acme",
        serial_number="AGV-1",
        timestamp="2024-03-11T11:40:03.12Z",
    )
    assert message.actions == actions
    assert message.timestamp == "2024-03-11T11:40:03.12Z"
    assert message.version == "2.0.0"


@pytest.mark.parametrize("state", list(ConnectionState))
def test_make_connection(state: ConnectionState) -> None:
    message = make_connection(
        state, header_id=1, manufacturer="Acme", serial_number="AGV-1", version="2.1.0"
    )
    wire = json.loads(encode(message))
    assert wire["connectionState"] == str(state)
    assert list(validator("2.1.0", "connection", strict=True).iter_errors(wire)) == []
