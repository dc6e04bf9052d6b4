"""decode/encode of 3.0.0 messages: Struct selection, round trips, errors."""

from __future__ import annotations

import json
from typing import Any

import pytest

from vda5050 import DecodeError, Topic, TopicError, TopicKind, decode, encode, subscription, v2, v3
from vda5050.headers import HeaderCounter
from vda5050.topics import kinds_of, parse_kind

from .samples import make_state
from .samples_v3 import (
    SAMPLE3_IDS,
    SAMPLES3,
    make_factsheet3,
    make_order3,
    make_responses3,
    make_state3,
    make_zone_set3,
)
from .support import V3_SCHEMA, load_schema


def _wire(message: Any) -> dict[str, Any]:
    result: dict[str, Any] = json.loads(encode(message))
    return result


def _bytes(value: Any) -> bytes:
    return json.dumps(value).encode()


@pytest.mark.parametrize(("kind", "message"), SAMPLES3, ids=SAMPLE3_IDS)
def test_round_trip(kind: TopicKind, message: v3.Message) -> None:
    decoded = decode(kind, encode(message), version="3.0.0")
    assert type(decoded) is type(message)
    assert decoded == message
    assert _wire(decoded) == _wire(message)


@pytest.mark.parametrize("version", ["3.0.0", "3.0.1", "3.1.0", "3"])
@pytest.mark.parametrize("kind", list(TopicKind))
def test_every_3_x_version_selects_the_3_0_structs(kind: TopicKind, version: str) -> None:
    message = next(m for k, m in SAMPLES3 if k == kind)
    decoded = decode(str(kind), encode(message), version=version)
    assert type(decoded) is v3.MESSAGE_TYPES[kind]
    assert type(decoded).__module__.startswith("vda5050.v3.")


def test_2_x_versions_keep_the_2_x_structs() -> None:
    state = decode(TopicKind.STATE, encode(make_state("2.1.0")), version="2.1.0")
    assert type(state) is v2.State


def test_zone_set_and_responses_exist_only_in_3_x() -> None:
    for kind, message in ((TopicKind.ZONE_SET, make_zone_set3()), (TopicKind.RESPONSES, None)):
        payload = encode(message or make_responses3())
        assert decode(kind, payload, version="3.0.0")
        for version in ("2.0.0", "2.1.0", "1.1.0"):
            with pytest.raises(DecodeError, match="unknown topic kind") as info:
                decode(kind, payload, version=version)
            assert info.value.kind == kind


def test_wire_names_are_the_3_0_names() -> None:
    order = _wire(make_order3())
    assert order["orderDescription"] == "pallet to dock"
    assert order["nodes"][0]["nodePosition"]["allowedDeviationXY"] == {
        "a": 0.5,
        "b": 0.3,
        "theta": 0.2,
    }
    edge = order["edges"][0]
    assert "startNodeId" not in edge
    assert edge["maximumSpeed"] == 1.5
    assert edge["maximumMobileRobotHeight"] == 2.2
    assert edge["minimumLoadHandlingDeviceHeight"] == 0.1
    assert edge["reachOrientationBeforeEntering"] is True
    assert edge["maxRotationSpeed"] == 0.5  # the schema keeps the 2.x name
    assert edge["corridor"]["corridorReferencePoint"] == "KINEMATIC_CENTER"
    assert order["nodes"][1]["actions"][0]["retriable"] is True
    assert order["nodes"][1]["actions"][0]["blockingType"] == "SINGLE"
    state = _wire(make_state3())
    assert state["mobileRobotPosition"]["localized"] is True
    assert state["powerSupply"]["stateOfCharge"] == 76.5
    assert state["powerSupply"]["range"] == 12000.0
    assert state["safetyState"] == {"activeEmergencyStop": "NONE", "fieldViolation": False}
    assert state["actionStates"][0]["actionStatus"] == "RETRIABLE"
    assert state["actionStates"][0]["actionResult"] == "gripper blocked"
    assert [a["actionId"] for a in state["instantActionStates"]] == ["c0", "i0"]
    assert state["zoneSets"][0]["zoneSetStatus"] == "ENABLED"
    factsheet = _wire(make_factsheet3())
    arrays = factsheet["protocolLimits"]["maximumArrayLengths"]
    assert arrays["zoneSet.zones"] == 20
    assert arrays["state.instantActionStates"] == 100
    envelope = factsheet["mobileRobotGeometry"]["envelopes2d"][0]
    assert envelope["envelope2dId"] == "default"
    assert envelope["vertices"][0] == {"x": 0.6, "y": 0.4}
    assert factsheet["mobileRobotGeometry"]["envelopes3d"][0]["envelope3dId"] == "hull"
    assert factsheet["typeSpecification"]["mobileRobotKinematics"] == "DIFFERENTIAL"


def test_unknown_fields_are_ignored() -> None:
    wire = _wire(make_state3())
    wire["vendorExtension"] = {"deep": [[{"x": 1}]]}
    wire["powerSupply"]["cellTemperatures"] = [21.5]
    wire["agvPosition"] = {"x": 1}  # a 2.x field is just unknown in 3.0
    assert decode(TopicKind.STATE, _bytes(wire), version="3.0.0") == make_state3()


def test_extensible_factsheet_values_decode() -> None:
    wire = _wire(make_factsheet3())
    wire["typeSpecification"]["mobileRobotKinematics"] = "MECANUM_X"
    wire["typeSpecification"]["navigationTypes"] = ["VENDOR_SLAM"]
    wire["mobileRobotGeometry"]["wheelDefinitions"][0]["type"] = "SPHERICAL"
    factsheet = decode(TopicKind.FACTSHEET, _bytes(wire), version="3.0.0")
    assert factsheet.type_specification.mobile_robot_kinematics == "MECANUM_X"


@pytest.mark.parametrize(
    ("kind", "field", "value"),
    [
        ("connection", "connectionState", "CONNECTIONBROKEN"),
        ("state", "operatingMode", "TEACHIN"),
        ("state", "operatingMode", "automatic"),
    ],
)
def test_2_x_and_1_1_spellings_are_rejected_in_3_0(kind: str, field: str, value: str) -> None:
    message = next(m for k, m in SAMPLES3 if k == kind)
    wire = _wire(message)
    wire[field] = value
    with pytest.raises(DecodeError) as info:
        decode(kind, _bytes(wire), version="3.0.0")
    assert info.value.path == f"$.{field}"


def test_a_2_x_state_is_not_a_3_0_state() -> None:
    with pytest.raises(DecodeError, match="missing required field"):
        decode(TopicKind.STATE, encode(make_state("2.1.0")), version="3.0.0")
    with pytest.raises(DecodeError):
        decode(TopicKind.STATE, encode(make_state3()), version="2.1.0")


_MISSING_CASES = [
    (kind, message, field)
    for kind, message in SAMPLES3
    for field in load_schema(V3_SCHEMA, kind).get("required", [])
    # Required by the schema, optional on input (display only, see the Struct docstring).
    if field in _wire(message) and (kind, field) != ("visualization", "referenceStateHeaderId")
]


@pytest.mark.parametrize(
    ("kind", "message", "field"),
    _MISSING_CASES,
    ids=[f"{k}-{f}-{i}" for i, (k, _, f) in enumerate(_MISSING_CASES)],
)
def test_missing_required_field_is_decode_error(
    kind: TopicKind, message: v3.Message, field: str
) -> None:
    wire = _wire(message)
    del wire[field]
    with pytest.raises(DecodeError) as info:
        decode(kind, _bytes(wire), version="3.0.0")
    assert field in info.value.reason


@pytest.mark.parametrize(
    ("mutate", "path"),
    [
        (lambda w: w["nodes"][0].update(sequenceId=-1), "$.nodes[0].sequenceId"),
        (lambda w: w.update(orderUpdateId=-3), "$.orderUpdateId"),
        (lambda w: w.update(headerId=2**32), "$.headerId"),
        (lambda w: w["nodes"][0]["nodePosition"]["allowedDeviationXY"].pop("b"), None),
        (lambda w: w["nodes"][1]["actions"][0].update(retriable="yes"), None),
        (lambda w: w["edges"][0]["corridor"].update(releaseLossBehavior="EVACUATE"), None),
        (lambda w: w["edges"][0].update(reachOrientationBeforeEntering=1), None),
    ],
)
def test_invalid_3_0_order_values_are_decode_errors(mutate: Any, path: str | None) -> None:
    wire = _wire(make_order3())
    mutate(wire)
    with pytest.raises(DecodeError) as info:
        decode(TopicKind.ORDER, _bytes(wire), version="3.0.0")
    if path is not None:
        assert info.value.path == path


def test_trajectory_degree_and_knots_are_optional_in_3_0() -> None:
    wire = _wire(make_order3())
    trajectory = wire["edges"][0]["trajectory"]
    del trajectory["degree"], trajectory["knotVector"]
    order = decode(TopicKind.ORDER, _bytes(wire), version="3.0.0")
    assert order.edges[0].trajectory is not None
    assert order.edges[0].trajectory.knot_vector is None
    assert "degree" not in _wire(order)["edges"][0]["trajectory"]


# --- topics and header counters know the 3.0 kinds ---------------------------------------


def test_topic_kinds_per_major_version() -> None:
    assert kinds_of(3) == set(TopicKind)
    assert kinds_of(2) == set(TopicKind) - {TopicKind.ZONE_SET, TopicKind.RESPONSES}
    assert kinds_of(1) == kinds_of(2)
    assert parse_kind("zoneSet", 3) is TopicKind.ZONE_SET
    assert parse_kind("responses", None) is TopicKind.RESPONSES
    with pytest.raises(TopicError, match="does not exist in protocol v2"):
        parse_kind("zoneSet")


def test_3_0_topics() -> None:
    topic = Topic.parse("vda5050/v3/Acme/AGV-001/zoneSet")
    assert topic.kind is TopicKind.ZONE_SET
    assert str(topic.with_kind(TopicKind.RESPONSES)) == "vda5050/v3/Acme/AGV-001/responses"
    with pytest.raises(TopicError):
        Topic.parse("vda5050/v2/Acme/AGV-001/responses")
    assert subscription("uagv", "v3", TopicKind.ZONE_SET) == "uagv/v3/+/+/zoneSet"
    with pytest.raises(TopicError):
        subscription("uagv", "v2", TopicKind.ZONE_SET)


def test_header_counter_counts_3_0_topics() -> None:
    counter = HeaderCounter()
    header = counter.header("Acme", "AGV-001", TopicKind.ZONE_SET, "3.0.0")
    assert header["header_id"] == 0
    assert header["timestamp"].endswith("Z")
    assert len(header["timestamp"].split(".")[1]) == 4  # .fffZ
    assert counter.next_id("Acme", "AGV-001", "responses") == 0
    assert counter.next_id("Acme", "AGV-001", "zoneSet") == 1
