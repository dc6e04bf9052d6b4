"""encode/decode: round trips, error reporting, encoding guards."""

from __future__ import annotations

import json
import math
from typing import Any

import pytest

from vda5050 import (
    Action,
    ActionParameter,
    BlockingType,
    Connection,
    DecodeError,
    EncodeError,
    Factsheet,
    InstantActions,
    Message,
    NodePosition,
    Order,
    State,
    TopicKind,
    VDA5050Error,
    Visualization,
    decode,
    encode,
)

from .factsheet_sample import make_factsheet
from .samples import ALL_SAMPLE_IDS, ALL_SAMPLES, make_order, make_state, samples
from .support import load_schema


def _wire(message: Message) -> dict[str, Any]:
    result: dict[str, Any] = json.loads(encode(message))
    return result


def _bytes(value: Any) -> bytes:
    return json.dumps(value).encode()


# --- round trips ------------------------------------------------------------------------


@pytest.mark.parametrize(("version", "kind", "message"), ALL_SAMPLES, ids=ALL_SAMPLE_IDS)
def test_round_trip(version: str, kind: TopicKind, message: Message) -> None:
    decoded = decode(kind, encode(message), version=version)
    assert type(decoded) is type(message)
    assert decoded == message
    # Same JSON values (ints sent in float fields come back as floats: 97 == 97.0).
    assert json.loads(encode(decoded)) == json.loads(encode(message))


@pytest.mark.parametrize(
    ("kind", "cls"),
    [
        (TopicKind.ORDER, Order),
        (TopicKind.INSTANT_ACTIONS, InstantActions),
        (TopicKind.STATE, State),
        (TopicKind.VISUALIZATION, Visualization),
        (TopicKind.CONNECTION, Connection),
        (TopicKind.FACTSHEET, Factsheet),
    ],
)
def test_kind_selects_struct_type(kind: TopicKind, cls: type[Message]) -> None:
    message = next(m for k, m in samples("2.1.0") if k == kind)
    assert type(decode(kind, encode(message))) is cls
    # A plain string kind works as well.
    assert type(decode(str(kind), encode(message))) is cls


def test_wire_names_are_camel_case() -> None:
    wire = _wire(make_order("2.0.0"))
    assert {"headerId", "serialNumber", "orderUpdateId", "nodes", "edges"} <= set(wire)
    node = wire["nodes"][0]
    assert node["nodePosition"]["allowedDeviationXY"] == 0.5
    assert node["nodePosition"]["allowedDeviationTheta"] == 0.1
    assert wire["edges"][0]["startNodeId"] == "n1"
    assert wire["edges"][0]["trajectory"]["knotVector"][-1] == 1.0
    state = _wire(make_state("2.0.0"))
    assert state["safetyState"] == {"eStop": "NONE", "fieldViolation": False}
    assert state["agvPosition"]["positionInitialized"] is True
    limits = _wire(make_factsheet("2.0.0"))["protocolLimits"]["maxArrayLens"]
    assert limits["order.nodes"] == 50
    assert limits["actions.actionsParameters"] == 10


def test_none_fields_are_omitted_and_required_empty_lists_kept() -> None:
    action = Action(action_type="beep", action_id="a1", blocking_type=BlockingType.NONE)
    assert json.loads(encode(action)) == {
        "actionType": "beep",
        "actionId": "a1",
        "blockingType": "NONE",
    }
    wire = _wire(make_order("2.0.0"))
    assert wire["nodes"][0]["actions"] == []  # required by the schema even when empty
    assert "zoneSetId" in wire
    assert "nodeDescription" not in wire["nodes"][1]


def test_trajectory_degree_is_always_sent() -> None:
    wire = _wire(make_state("2.0.0"))
    assert wire["edgeStates"][0]["trajectory"]["degree"] == 1


def test_2_0_edge_state_trajectory_without_degree_decodes_with_default() -> None:
    # 2.0 state schema makes degree optional; the documented default is 1.
    wire = _wire(make_state("2.0.0"))
    del wire["edgeStates"][0]["trajectory"]["degree"]
    state = decode(TopicKind.STATE, _bytes(wire))
    assert state.edge_states[0].trajectory is not None
    assert state.edge_states[0].trajectory.degree == 1


def test_action_parameter_values_keep_their_json_type() -> None:
    order = decode(TopicKind.ORDER, encode(make_order("2.0.0")))
    values = {p.key: p.value for p in order.nodes[1].actions[0].action_parameters or []}
    assert values["retries"] == 3
    assert type(values["retries"]) is int
    assert type(values["height"]) is float
    assert values["verify"] is True
    assert values["lhd"] == ["front", "rear"]
    assert values["extra"] == {"nested": {"list": [1, 2.5, "x", False]}}


def test_enums_decode_to_enum_members() -> None:
    state = decode(TopicKind.STATE, encode(make_state("2.0.0")))
    assert type(state.operating_mode).__name__ == "OperatingMode"
    assert state.safety_state.e_stop.name == "NONE"


def test_unknown_fields_are_ignored() -> None:
    wire = _wire(make_state("2.1.0"))
    wire["vendorExtension"] = {"deep": [[{"x": 1}]], "n": 1e300}
    wire["batteryState"]["cellTemperatures"] = [21.5, 22.0]
    wire["errors"][0]["errorDescriptionTranslations"] = [{"translationKey": "de"}]
    assert decode(TopicKind.STATE, _bytes(wire), version="2.1.0") == make_state("2.1.0")


def test_decode_accepts_bytearray_memoryview_and_str() -> None:
    payload = encode(make_order("2.0.0"))
    expected = decode(TopicKind.ORDER, payload)
    assert decode(TopicKind.ORDER, bytearray(payload)) == expected
    assert decode(TopicKind.ORDER, memoryview(payload)) == expected
    assert decode(TopicKind.ORDER, payload.decode()) == expected


def test_decode_accepts_2_1_fields_under_2_0_version() -> None:
    # One Struct set: a 2.1 vehicle misconfigured as 2.0 must not be rejected.
    state = decode(TopicKind.STATE, encode(make_state("2.1.0")), version="2.0.0")
    assert state.maps is not None


# --- error reporting --------------------------------------------------------------------


def test_decode_error_names_kind_path_and_reason() -> None:
    wire = _wire(make_order("2.0.0"))
    wire["nodes"].append(dict(wire["nodes"][0], nodeId=5))
    with pytest.raises(DecodeError) as info:
        decode(TopicKind.ORDER, _bytes(wire))
    error = info.value
    assert error.kind == "order"
    assert error.path == "$.nodes[3].nodeId"
    assert "str" in error.reason
    assert "$.nodes[3].nodeId" in str(error)
    assert "order" in str(error)
    assert isinstance(error, VDA5050Error)


def _required(kind: str) -> list[str]:
    # Required in both versions, so missing must be an error whatever the version.
    sets = [set(load_schema(v, kind).get("required", [])) for v in ("2.0.0", "2.1.0")]
    return sorted(set.intersection(*sets))


_MISSING_CASES = [
    (version, kind, message, field)
    for version, kind, message in ALL_SAMPLES
    for field in _required(kind)
    if field in _wire(message)
]


@pytest.mark.parametrize(
    ("version", "kind", "message", "field"),
    _MISSING_CASES,
    ids=[f"{v}-{k}-{f}" for v, k, _, f in _MISSING_CASES],
)
def test_missing_required_field_is_decode_error(
    version: str, kind: TopicKind, message: Message, field: str
) -> None:
    wire = _wire(message)
    del wire[field]
    with pytest.raises(DecodeError) as info:
        decode(kind, _bytes(wire), version=version)
    assert field in info.value.reason


def test_missing_nested_required_field_reports_path() -> None:
    wire = _wire(make_state("2.0.0"))
    del wire["batteryState"]["charging"]
    with pytest.raises(DecodeError) as info:
        decode(TopicKind.STATE, _bytes(wire))
    assert info.value.path == "$.batteryState"
    assert "charging" in info.value.reason


def _wrong_value(value: Any) -> Any:
    if isinstance(value, bool):
        return "true"
    if isinstance(value, int | float):
        return str(value)
    if isinstance(value, str):
        return 12
    if isinstance(value, list):
        return {"not": "a list"}
    return [value]


_WRONG_TYPE_CASES = [
    (kind, message, field)
    for version, kind, message in ALL_SAMPLES
    if version == "2.1.0"
    for field in _wire(message)
]


@pytest.mark.parametrize(
    ("kind", "message", "field"),
    _WRONG_TYPE_CASES,
    ids=[f"{k}-{f}-{i}" for i, (k, _, f) in enumerate(_WRONG_TYPE_CASES)],
)
def test_wrong_type_is_decode_error_at_field(kind: TopicKind, message: Message, field: str) -> None:
    wire = _wire(message)
    wire[field] = _wrong_value(wire[field])
    with pytest.raises(DecodeError) as info:
        decode(kind, _bytes(wire), version="2.1.0")
    assert info.value.path == f"$.{field}"


@pytest.mark.parametrize(
    ("mutate", "path"),
    [
        (lambda w: w["nodes"][0].update(sequenceId=-1), "$.nodes[0].sequenceId"),
        (lambda w: w.update(orderUpdateId=-3), "$.orderUpdateId"),
        (lambda w: w.update(headerId=2**32), "$.headerId"),
        (lambda w: w.update(headerId=1.5), "$.headerId"),
        (lambda w: w["edges"][0].update(orientationType="SIDEWAYS"), "$.edges[0].orientationType"),
        (lambda w: w["nodes"][1]["actions"][0].update(blockingType="none"), None),
        (lambda w: w["nodes"][1]["actions"][0]["actionParameters"][0].update(value=None), None),
        (lambda w: w["nodes"][0]["nodePosition"].pop("mapId"), "$.nodes[0].nodePosition"),
        (lambda w: w["edges"][0]["trajectory"].update(knotVector=["a"]), None),
    ],
)
def test_invalid_values_are_decode_errors(mutate: Any, path: str | None) -> None:
    wire = _wire(make_order("2.1.0"))
    mutate(wire)
    with pytest.raises(DecodeError) as info:
        decode(TopicKind.ORDER, _bytes(wire))
    if path is not None:
        assert info.value.path == path


def test_unknown_kind_and_unsupported_version_are_decode_errors() -> None:
    payload = encode(make_order("2.0.0"))
    with pytest.raises(DecodeError) as info:
        decode("zoneSet", payload)  # a 3.0 topic, unknown in 2.x
    assert info.value.kind == "zoneSet"
    with pytest.raises(DecodeError) as info:
        decode("nonsense", payload)
    assert info.value.kind == "nonsense"
    with pytest.raises(DecodeError, match="unsupported protocol version"):
        decode(TopicKind.ORDER, payload, version="4.0.0")
    with pytest.raises(DecodeError, match="malformed protocol version"):
        decode(TopicKind.ORDER, payload, version="two")


def test_a_2_x_order_is_not_a_3_0_order() -> None:
    # 3.0 is not wire-compatible: the ellipse allowedDeviationXY rejects the 2.x number.
    with pytest.raises(DecodeError) as info:
        decode(TopicKind.ORDER, encode(make_order("2.0.0")), version="3.0.0")
    assert info.value.path == "$.nodes[0].nodePosition.allowedDeviationXY"


# --- encode -------------------------------------------------------------------------------


@pytest.mark.parametrize("bad", [math.nan, math.inf, -math.inf])
def test_encode_rejects_non_finite_float_field(bad: float) -> None:
    order = make_order("2.0.0")
    order.nodes[2].node_position = NodePosition(x=bad, y=0.0, map_id="m")
    with pytest.raises(EncodeError) as info:
        encode(order)
    assert info.value.path == "$.nodes[2].nodePosition.x"


def test_encode_rejects_non_finite_nested_parameter_value() -> None:
    order = make_order("2.0.0")
    order.nodes[1].actions[0].action_parameters = [
        ActionParameter(key="k", value={"a": [1.0, {"b": math.nan}]})
    ]
    with pytest.raises(EncodeError) as info:
        encode(order)
    assert info.value.path == "$.nodes[1].actions[0].actionParameters[0].value.a[1].b"
    assert isinstance(info.value, VDA5050Error)


def test_encode_never_writes_null_for_nan() -> None:
    state = make_state("2.0.0")
    state.battery_state.battery_charge = math.nan
    with pytest.raises(EncodeError):
        encode(state)


def test_encode_with_null_text_but_finite_floats_succeeds() -> None:
    # "null" in the output sends encode down its slow path (NaN is written as null); a string
    # saying null and a field left None are no reason to reject the message.
    state = make_state("2.0.0")
    state.order_id = "null"
    state.battery_state.reach = None
    assert json.loads(encode(state))["orderId"] == "null"


def test_encode_reports_non_finite_before_other_encode_errors() -> None:
    state = make_state("2.0.0")
    state.order_id = "\ud800"
    state.battery_state.battery_charge = math.inf
    with pytest.raises(EncodeError) as info:
        encode(state)
    assert info.value.path == "$.batteryState.batteryCharge"


def test_encode_rejects_unencodable_strings() -> None:
    state = make_state("2.0.0")
    state.order_id = "\ud800"
    with pytest.raises(EncodeError):
        encode(state)


def test_encode_handles_deeply_nested_parameter_values() -> None:
    value: Any = 1.0
    for _ in range(5000):
        value = [value]
    action = Action(
        action_type="x",
        action_id="a",
        blocking_type=BlockingType.NONE,
        action_parameters=[ActionParameter(key="k", value=value)],
    )
    # The non-finite scan is iterative; msgspec's recursion limit must surface as
    # EncodeError, never as RecursionError.
    with pytest.raises(EncodeError, match="nested too deeply"):
        encode(action)


def test_encode_scan_finds_nan_below_recursion_limit_depth() -> None:
    value: Any = math.nan
    for _ in range(5000):
        value = [value]
    action = Action(
        action_type="x",
        action_id="a",
        blocking_type=BlockingType.NONE,
        action_parameters=[ActionParameter(key="k", value=value)],
    )
    with pytest.raises(EncodeError) as info:
        encode(action)
    assert info.value.path is not None
    assert info.value.path.endswith("[0]" * 5000)
