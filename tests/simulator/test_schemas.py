"""Every message the simulator emits validates against the official schema of its version."""

from __future__ import annotations

import copy
import json
import re
from functools import cache
from pathlib import Path
from typing import Any

import jsonschema
import pytest

from simulator import Misbehaviour
from tests.simulator.builders import (
    action,
    finished,
    instant,
    make_order,
    make_vehicle,
    run,
    run_until,
)
from vda5050 import State, decode, encode
from vda5050.enums import BlockingType, ConnectionState, ErrorLevel, OperatingMode, TopicKind

SCHEMAS = Path("/work/shared/vda5050/schemas")
VERSIONS = ["2.0.0", "2.1.0"]
TIMESTAMP = re.compile(r"\d{4}-\d\d-\d\dT\d\d:\d\d:\d\d\.\d\dZ")  # 2.x: .ffZ


def _fix_blocking_types(schema: dict[str, Any]) -> dict[str, Any]:
    """Upstream bug: ``agvActions[].blockingTypes`` is ``type: array`` with a string
    ``enum``, which no array can satisfy. Move the enum to ``items`` (what the document
    means); everything else stays verbatim."""
    fixed = copy.deepcopy(schema)
    spec = fixed["properties"]["protocolFeatures"]["properties"]["agvActions"]["items"]
    blocking = spec["properties"]["blockingTypes"]
    blocking["items"] = {"type": "string", "enum": blocking.pop("enum")}
    return fixed


@cache
def validator(version: str, kind: str) -> jsonschema.Draft202012Validator:
    # REFERENCE §7: some upstream files have trailing commas.
    text = (SCHEMAS / version / f"{kind}.schema").read_text(encoding="utf-8")
    schema = json.loads(re.sub(r",(\s*[}\]])", r"\1", text))
    if kind == "factsheet":
        schema = _fix_blocking_types(schema)
    jsonschema.Draft202012Validator.check_schema(schema)
    # No format checker: "date-time" needs an optional package; the timestamp format is
    # asserted with a stricter regex below instead.
    return jsonschema.Draft202012Validator(schema)


def _assert_valid(version: str, kind: TopicKind, payload: bytes) -> None:
    data = json.loads(payload)
    errors = sorted(validator(version, str(kind)).iter_errors(data), key=str)
    assert not errors, f"{kind} invalid for {version}: {errors[0]}"
    if "timestamp" in data:
        assert TIMESTAMP.fullmatch(data["timestamp"]), data["timestamp"]
    decode(kind, payload, version=version)  # and our own decoder accepts it back


def _scenario_messages(version: str) -> list[tuple[TopicKind, bytes]]:
    """Drive a vehicle through most features and collect everything it would publish."""
    vehicle = make_vehicle(version=version)
    out: list[tuple[TopicKind, bytes]] = [
        (TopicKind.CONNECTION, encode(vehicle.build_connection(state))) for state in ConnectionState
    ]
    out.append((TopicKind.FACTSHEET, encode(vehicle.build_factsheet())))

    def collect(states: list[State]) -> None:
        out.extend((TopicKind.STATE, encode(s)) for s in states)
        out.append((TopicKind.VISUALIZATION, encode(vehicle.build_visualization())))

    collect([vehicle.build_state()])
    vehicle.on_order(make_order("bad", ["n1", "n2"], actions={"n2": [action("dance", "x")]}))
    vehicle.on_instant_actions(instant(action("cancelOrder", "c0")))
    vehicle.inject_error("injected", ErrorLevel.FATAL, "fault injection")
    collect([vehicle.build_state()])
    pick = action("pick", "p1", loadId="L1", loadType="EPAL", lhd="default")
    drop = action("drop", "d1", BlockingType.SOFT)
    vehicle.on_order(
        make_order("o1", ["n1", "n2", "n3", "n4"], released=3, actions={"n2": [pick], "n3": [drop]})
    )
    collect([vehicle.build_state()])
    collect(run(vehicle, 3.0))
    vehicle.on_instant_actions(instant(action("startPause", "sp"), action("stopPause", "rp")))
    collect(run_until(vehicle, lambda v: not v.pending[0].released if v.pending else True))
    vehicle.on_instant_actions(instant(action("cancelOrder", "c1")))
    collect(run_until(vehicle, finished))
    vehicle.on_instant_actions(instant(action("startCharging", "ch")))
    collect(run(vehicle, 1.0))
    return out


@pytest.mark.parametrize("version", VERSIONS)
def test_every_emitted_message_validates(version: str) -> None:
    messages = _scenario_messages(version)
    kinds = {kind for kind, _ in messages}
    assert kinds == {
        TopicKind.STATE,
        TopicKind.CONNECTION,
        TopicKind.FACTSHEET,
        TopicKind.VISUALIZATION,
    }
    for kind, payload in messages:
        _assert_valid(version, kind, payload)
    # The scenario really exercised the interesting optional parts of the state.
    states = [json.loads(p) for k, p in messages if k is TopicKind.STATE]
    assert any(s["loads"] for s in states)
    assert any(s["errors"] for s in states)
    assert any(s["nodeStates"] and s["edgeStates"] for s in states)
    assert ("maps" in states[0]) is (version == "2.1.0")


@pytest.mark.parametrize("version", VERSIONS)
def test_factsheet_describes_supported_actions(version: str) -> None:
    factsheet = json.loads(encode(make_vehicle(version=version).build_factsheet()))
    spec = factsheet["typeSpecification"]
    assert (spec["agvKinematic"], spec["agvClass"]) == ("DIFF", "CARRIER")
    assert spec["localizationTypes"] == ["NATURAL"]
    assert spec["navigationTypes"] == ["AUTONOMOUS"]
    actions = {a["actionType"]: a for a in factsheet["protocolFeatures"]["agvActions"]}
    assert set(actions) >= {
        "pick",
        "drop",
        "startCharging",
        "stopCharging",
        "cancelOrder",
        "startPause",
        "stopPause",
        "stateRequest",
        "factsheetRequest",
        "initPosition",
    }
    assert actions["pick"]["actionScopes"] == ["NODE"]
    assert "INSTANT" in actions["initPosition"]["actionScopes"]
    init_keys = {p["key"] for p in actions["initPosition"]["actionParameters"]}
    assert init_keys == {"x", "y", "theta", "mapId", "lastNodeId"}
    assert factsheet["agvGeometry"]["envelopes2d"][0]["polygonPoints"]
    assert ("vehicleConfig" in factsheet) is (version == "2.1.0")


def test_timestamps_match_the_documented_format() -> None:
    payload = json.loads(encode(make_vehicle().build_state()))
    assert TIMESTAMP.fullmatch(payload["timestamp"])


def test_validator_is_not_vacuous() -> None:
    state = json.loads(encode(make_vehicle().build_state()))
    del state["errors"]
    state["operatingMode"] = "FLYING"
    problems = list(validator("2.0.0", "state").iter_errors(state))
    assert len(problems) == 2


@pytest.mark.parametrize("version", VERSIONS)
def test_misbehaving_vehicle_messages_validate(version: str) -> None:
    plan = Misbehaviour(
        reject_orders="vendorRefusal",
        reject_count=1,
        stale_states=1.0,
        duplicate_states=1.0,
        fail_actions=("pick",),
        fatal_after_nodes=2,
        mode=OperatingMode.SERVICE,
        mode_at=30.0,
    )
    vehicle = make_vehicle(version=version, misbehaviour=plan)
    states = vehicle.build_states()
    vehicle.on_order(make_order("refused", ["n1", "n2"]))
    states += vehicle.build_states()
    vehicle.on_order(make_order("o1", ["n1", "n2", "n3"], actions={"n2": [action("pick", "p1")]}))
    vehicle.on_instant_actions(instant(action("logReport", "l1", reason="test")))
    for _ in range(400):
        vehicle.tick(0.1)
        if vehicle.take_state_due():
            states += vehicle.build_states()
    payloads = [encode(s) for s in states]
    for payload in payloads:
        _assert_valid(version, TopicKind.STATE, payload)
    decoded = [json.loads(p) for p in payloads]
    errors = {(e["errorType"], e["errorLevel"]) for s in decoded for e in s["errors"]}
    assert errors >= {
        ("vendorRefusal", "WARNING"),
        ("actionFailed", "WARNING"),
        ("simulatedFatalError", "FATAL"),
    }
    assert decoded[-1]["operatingMode"] == "SERVICE"
    factsheet = encode(vehicle.build_factsheet())
    _assert_valid(version, TopicKind.FACTSHEET, factsheet)
