"""Everything a 3.0 simulated vehicle emits validates against the 3.0.0-main schemas and
adapts to valid 2.x Structs (what master control works with)."""

from __future__ import annotations

import json
import re
from functools import cache
from pathlib import Path
from typing import Any

import jsonschema
import pytest

from simulator import Misbehaviour, wire
from tests.simulator.builders import (
    action,
    finished,
    instant3,
    make_order3,
    make_vehicle,
    run3,
    run3_until,
    send3,
)
from vda5050 import TopicKind, decode, encode, v3
from vda5050.adapt import factsheet_v3_to_v2, state_v3_to_v2, visualization_v3_to_v2
from vda5050.enums import BlockingType, ConnectionState, ErrorLevel, OperatingMode

SCHEMAS = Path("/work/shared/vda5050/schemas/3.0.0-main")
TIMESTAMP_3 = re.compile(r"\d{4}-\d\d-\d\dT\d\d:\d\d:\d\d\.\d{3}Z")  # 3.0: .fffZ


def _strict(schema: Any) -> Any:
    """additionalProperties false everywhere: catches misspelt and 2.x-only field names."""
    if isinstance(schema, dict):
        result = {key: _strict(value) for key, value in schema.items()}
        if "properties" in result and "additionalProperties" not in result:
            result["additionalProperties"] = False
        return result
    if isinstance(schema, list):
        return [_strict(item) for item in schema]
    return schema


@cache
def validator(kind: str, strict: bool) -> jsonschema.Draft202012Validator:
    schema = json.loads((SCHEMAS / f"{kind}.schema").read_text(encoding="utf-8"))
    if strict:
        schema = _strict(schema)
    jsonschema.Draft202012Validator.check_schema(schema)
    return jsonschema.Draft202012Validator(schema)


def _assert_valid(kind: TopicKind, payload: bytes) -> None:
    data = json.loads(payload)
    for strict in (False, True):
        errors = sorted(validator(str(kind), strict).iter_errors(data), key=str)
        assert not errors, f"{kind} invalid (strict={strict}): {errors[0]}"
    assert data["version"] == "3.0.0"
    assert TIMESTAMP_3.fullmatch(data["timestamp"]), data["timestamp"]
    decode(kind, payload, version="3.0.0")  # and our own decoder accepts it back


def _scenario() -> list[tuple[TopicKind, bytes]]:
    """Drive a 3.0 vehicle through most features; collect everything it would publish."""
    vehicle = make_vehicle(version="3.0.0")
    out: list[tuple[TopicKind, bytes]] = [
        (TopicKind.CONNECTION, encode(wire.connection(vehicle, state))) for state in ConnectionState
    ]
    out.append((TopicKind.FACTSHEET, encode(wire.factsheet(vehicle))))

    def collect(states: list[v3.State]) -> None:
        out.extend((TopicKind.STATE, encode(s)) for s in states)
        out.append((TopicKind.VISUALIZATION, encode(wire.visualization(vehicle))))

    collect(wire.states(vehicle))  # type: ignore[arg-type]
    send3(vehicle, make_order3("bad", ["n1", "n2"], actions={"n2": [action("dance", "x")]}))
    send3(vehicle, instant3(action("cancelOrder", "c0")))
    vehicle.inject_error("injected", ErrorLevel.FATAL, "fault injection")
    collect(wire.states(vehicle))  # type: ignore[arg-type]
    pick = action("pick", "p1", loadId="L1", loadType="EPAL", lhd="default")
    drop = action("drop", "d1", BlockingType.SOFT)
    look = action("detectObject", "o1", BlockingType.NONE)
    order = make_order3(
        "o1", ["n1", "n2", "n3", "n4"], released=3, actions={"n2": [pick, look], "n3": [drop]}
    )
    order.nodes[1].actions[1].blocking_type = v3.BlockingType.SINGLE
    send3(vehicle, order)
    collect(wire.states(vehicle))  # type: ignore[arg-type]
    collect(run3(vehicle, 3.0))
    send3(vehicle, instant3(action("startPause", "sp"), action("stopPause", "rp")))
    collect(run3_until(vehicle, lambda v: not v.pending[0].released if v.pending else True))
    send3(vehicle, instant3(action("cancelOrder", "c1")))
    collect(run3_until(vehicle, finished))
    send3(vehicle, instant3(action("startCharging", "ch"), action("clearInstantActions", "cl")))
    collect(run3(vehicle, 1.0))
    return out


def test_every_emitted_message_validates() -> None:
    messages = _scenario()
    assert {kind for kind, _ in messages} == {
        TopicKind.STATE,
        TopicKind.CONNECTION,
        TopicKind.FACTSHEET,
        TopicKind.VISUALIZATION,
    }
    for kind, payload in messages:
        _assert_valid(kind, payload)
    states = [json.loads(p) for k, p in messages if k is TopicKind.STATE]
    # The scenario really exercised the interesting parts of the 3.0 state.
    assert any(s["loads"] for s in states)
    assert any(s["errors"] for s in states)
    assert any(s["nodeStates"] and s["edgeStates"] for s in states)
    assert any(s["instantActionStates"] for s in states)
    assert any(s["actionStates"] for s in states)
    assert all("maps" in s for s in states)
    levels = {e["errorType"]: e["errorLevel"] for s in states for e in s["errors"]}
    assert levels["INVALID_ORDER_ACTION"] == "WARNING"
    assert levels["injected"] == "FATAL"
    visual = [json.loads(p) for k, p in messages if k is TopicKind.VISUALIZATION]
    assert all("referenceStateHeaderId" in v for v in visual)
    assert visual[-1]["referenceStateHeaderId"] == states[-1]["headerId"]
    connections = {json.loads(p)["connectionState"] for k, p in messages if k == "connection"}
    assert connections == {"ONLINE", "OFFLINE", "CONNECTION_BROKEN"}


def test_emitted_states_and_factsheet_adapt_to_valid_2_x_structs() -> None:
    # What master control will do with them: one 2.x model.
    for kind, payload in _scenario():
        message = decode(kind, payload, version="3.0.0")
        if isinstance(message, v3.State):
            adapted: Any = state_v3_to_v2(message)
        elif isinstance(message, v3.Factsheet):
            adapted = factsheet_v3_to_v2(message)
        elif isinstance(message, v3.Visualization):
            adapted = visualization_v3_to_v2(message)
        else:
            continue
        assert decode(kind, encode(adapted), version="2.1.0") == adapted


def test_factsheet_describes_3_0_actions() -> None:
    factsheet = wire.factsheet(make_vehicle(version="3.0.0"))
    assert isinstance(factsheet, v3.Factsheet)
    spec = factsheet.type_specification
    assert (spec.mobile_robot_kinematics, spec.mobile_robot_class) == ("DIFFERENTIAL", "CARRIER")
    assert spec.navigation_types == ["FREELY_NAVIGATING"]
    actions = {a.action_type: a for a in factsheet.protocol_features.mobile_robot_actions}
    assert "initializePosition" in actions
    assert "initPosition" not in actions
    assert {"detectObject", "clearInstantActions", "cancelOrder"} <= set(actions)
    assert actions["detectObject"].blocking_types is not None
    assert v3.BlockingType.SINGLE in actions["detectObject"].blocking_types
    assert actions["cancelOrder"].blocking_types == [v3.BlockingType.NONE]
    assert actions["pick"].pause_allowed
    assert not actions["pick"].cancel_allowed
    cancel_keys = {p.key for p in actions["cancelOrder"].action_parameters or []}
    assert cancel_keys == {"orderId"}


@pytest.mark.parametrize("version", ["2.0.0", "2.1.0"])
def test_2_x_factsheets_do_not_offer_3_0_only_actions(version: str) -> None:
    factsheet = wire.factsheet(make_vehicle(version=version))
    names = {
        a["actionType"] for a in json.loads(encode(factsheet))["protocolFeatures"]["agvActions"]
    }
    assert "detectObject" not in names
    assert "clearInstantActions" not in names
    assert "initPosition" in names


def test_misbehaving_3_0_vehicle_messages_validate() -> None:
    plan = Misbehaviour(
        reject_orders="orderError",
        reject_count=1,
        stale_states=1.0,
        duplicate_states=1.0,
        reorder_states=0.5,
        fail_actions=("pick",),
        fatal_after_nodes=2,
        mode=OperatingMode.SERVICE,
        mode_at=30.0,
        seed=3,
    )
    vehicle = make_vehicle(version="3.0.0", misbehaviour=plan)
    states: list[v3.State] = list(wire.states(vehicle))  # type: ignore[arg-type]
    send3(vehicle, make_order3("refused", ["n1", "n2"]))
    states += wire.states(vehicle)  # type: ignore[arg-type]
    send3(vehicle, make_order3("o1", ["n1", "n2", "n3"], actions={"n2": [action("pick", "p1")]}))
    states += run3(vehicle, 40.0)
    for state in states:
        _assert_valid(TopicKind.STATE, encode(state))
    errors = {(e.error_type, e.error_level) for s in states for e in s.errors}
    assert ("INVALID_ORDER_ACTION", "WARNING") in errors  # scripted "orderError", in 3.0
    assert ("actionFailed", "WARNING") in errors
    assert ("simulatedFatalError", "FATAL") in errors
    assert states[-1].operating_mode is v3.OperatingMode.SERVICE
    assert len({s.header_id for s in states}) < len(states)  # duplicates happened


@pytest.mark.parametrize("version", ["2.0.0", "2.1.0", "3.0.0"])
def test_a_faster_than_real_time_vehicle_declares_its_wall_clock_speed(version: str) -> None:
    # control plans on the wall clock: at time scale 4 a 1 m/s vehicle covers 4 m a second
    factsheet = json.loads(encode(wire.factsheet(make_vehicle(version=version, time_scale=4.0))))
    physical = factsheet["physicalParameters"]
    assert physical.get("speedMax", physical.get("maximumSpeed")) == 4.0
    real_time = json.loads(encode(wire.factsheet(make_vehicle(version=version))))
    assert real_time["physicalParameters"] != physical
