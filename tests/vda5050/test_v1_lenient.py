"""1.1 accepted on input: lower-case enums and ``informations`` decode into the 2.x Structs."""

from __future__ import annotations

import json
from typing import Any

import pytest

from vda5050 import (
    ActionStatus,
    BlockingType,
    ConnectionState,
    DecodeError,
    ErrorLevel,
    EStop,
    InfoLevel,
    OperatingMode,
    TopicKind,
    decode,
    encode,
    v2,
)
from vda5050.lenient import ENUM_KEYS, normalise_v1

from .factsheet_sample import make_factsheet
from .samples import make_connection, make_instant_actions, make_order, make_state


def _lower_case_1_1(message: Any, version: str = "1.1.0") -> dict[str, Any]:
    """A 2.0 sample re-spelt the way 1.1 vehicles send it."""
    wire: dict[str, Any] = json.loads(encode(message))
    wire["version"] = version
    spelling = {
        "AUTOMATIC": "automatic",
        "WARNING": "warning",
        "FATAL": "fatal",
        "FINISHED": "finished",
        "RUNNING": "running",
        "NONE": "none",
        "HARD": "hard",
        "SOFT": "soft",
        "INFO": "info",
        "DEBUG": "debug",
        "CONNECTIONBROKEN": "connectionBroken",
        "AUTOACK": "autoAck",
    }
    stack: list[Any] = [wire]
    while stack:
        value = stack.pop()
        items = value.items() if isinstance(value, dict) else enumerate(value)
        for key, item in list(items):
            if isinstance(item, str) and key in ENUM_KEYS:
                value[key] = spelling.get(item, item.lower())
            elif isinstance(item, dict | list) and key != "value":
                stack.append(item)
    return wire


def _bytes(value: Any) -> bytes:
    return json.dumps(value).encode()


def test_1_1_state_with_lower_case_enums_and_informations() -> None:
    wire = _lower_case_1_1(make_state("2.0.0"))
    wire["informations"] = wire.pop("information")
    wire["safetyState"]["eStop"] = "autoAck"
    assert wire["operatingMode"] == "automatic"
    assert wire["errors"][0]["errorLevel"] == "warning"
    state = decode(TopicKind.STATE, _bytes(wire), version="1.1.0")
    assert type(state) is v2.State
    assert state.version == "1.1.0"
    assert state.operating_mode is OperatingMode.AUTOMATIC
    assert state.errors[0].error_level is ErrorLevel.WARNING
    assert state.errors[1].error_level is ErrorLevel.FATAL
    assert state.safety_state.e_stop is EStop.AUTOACK
    assert state.information is not None
    assert state.information[0].info_level is InfoLevel.INFO
    assert {a.action_status for a in state.action_states} == set(ActionStatus)
    # Apart from the version it is exactly the 2.0 message.
    expected = make_state("2.0.0")
    expected.version = "1.1.0"
    expected.safety_state.e_stop = EStop.AUTOACK
    assert state == expected


def test_1_1_upper_case_input_decodes_too() -> None:
    wire = json.loads(encode(make_state("2.0.0")))
    wire["version"] = "1.1"
    assert decode(TopicKind.STATE, _bytes(wire), version="1.1").order_id == "order-42"


def test_1_1_order_instant_actions_and_connection() -> None:
    order = decode(TopicKind.ORDER, _bytes(_lower_case_1_1(make_order("2.0.0"))), version="1.1.0")
    assert order.nodes[1].actions[0].blocking_type is BlockingType.HARD
    assert order.nodes[2].actions[0].blocking_type is BlockingType.SOFT
    instant = decode(
        TopicKind.INSTANT_ACTIONS,
        _bytes(_lower_case_1_1(make_instant_actions("2.0.0"))),
        version="1.1.0",
    )
    assert {a.blocking_type for a in instant.actions} == {BlockingType.NONE}
    for state in ConnectionState:
        wire = _lower_case_1_1(make_connection("2.0.0", state))
        connection = decode(TopicKind.CONNECTION, _bytes(wire), version="1.1.0")
        assert connection.connection_state is state


def test_free_form_parameter_values_are_not_rewritten() -> None:
    wire = _lower_case_1_1(make_order("2.0.0"))
    params = wire["nodes"][1]["actions"][0]["actionParameters"]
    params.append({"key": "mode", "value": {"blockingType": "soft", "eStop": "none"}})
    params.append({"key": "blockingType", "value": "soft"})
    order = decode(TopicKind.ORDER, _bytes(wire), version="1.1.0")
    values = {p.key: p.value for p in order.nodes[1].actions[0].action_parameters or []}
    assert values["mode"] == {"blockingType": "soft", "eStop": "none"}
    assert values["blockingType"] == "soft"


def test_1_1_has_no_factsheet() -> None:
    with pytest.raises(DecodeError, match="unknown topic kind") as info:
        decode(TopicKind.FACTSHEET, encode(make_factsheet("2.0.0")), version="1.1.0")
    assert info.value.kind == "factsheet"


def test_lenient_path_still_validates() -> None:
    wire = _lower_case_1_1(make_state("2.0.0"))
    wire["operatingMode"] = "flying"
    with pytest.raises(DecodeError) as info:
        decode(TopicKind.STATE, _bytes(wire), version="1.1.0")
    assert info.value.path == "$.operatingMode"
    del wire["operatingMode"]
    with pytest.raises(DecodeError, match="operatingMode"):
        decode(TopicKind.STATE, _bytes(wire), version="1.1.0")
    wire = _lower_case_1_1(make_order("2.0.0"))
    wire["nodes"][0]["nodeId"] = 5
    with pytest.raises(DecodeError) as info:
        decode(TopicKind.ORDER, _bytes(wire), version="1.1.0")
    assert info.value.path == "$.nodes[0].nodeId"


def test_2_x_stays_strict_about_spelling() -> None:
    wire = _lower_case_1_1(make_state("2.0.0"), version="2.0.0")
    with pytest.raises(DecodeError):
        decode(TopicKind.STATE, _bytes(wire), version="2.0.0")


def test_normalise_v1_is_iterative_and_in_place() -> None:
    deep: Any = {"errorLevel": "warning"}
    for _ in range(5000):
        deep = [deep]
    document = {"errors": deep, "informations": [], "operatingMode": "manual"}
    assert normalise_v1(TopicKind.STATE, document) is document
    assert document["operatingMode"] == "MANUAL"
    assert "information" in document
    assert "informations" not in document
    inner = document["errors"]
    while isinstance(inner, list):
        inner = inner[0]
    assert inner == {"errorLevel": "WARNING"}
    # Non-state documents keep an "informations" key (unknown there anyway).
    other = {"informations": 1}
    assert normalise_v1(TopicKind.ORDER, other) == {"informations": 1}
