"""``--misbehave`` / ``--script`` parsing and how the plan reaches the vehicles."""

from __future__ import annotations

import json
from dataclasses import fields
from pathlib import Path

import pytest

from simulator import FleetConfig, Layout, Misbehaviour, SimulatedFleet
from simulator.__main__ import build_parser, main
from simulator.fleet import build_vehicles
from simulator.misbehaviour import KEYS, build_plan, parse_spec
from tests.simulator.builders import LAYOUT_DICT
from vda5050.enums import OperatingMode


def test_parse_spec_splits_serial_and_pairs() -> None:
    assert parse_spec("AGV-2:reject_orders=orderError,reject_count=2") == (
        "AGV-2",
        [("reject_orders", "orderError"), ("reject_count", "2")],
    )
    # Serial numbers may contain ':' (REFERENCE §2), keys never do.
    assert parse_spec("plant:AGV:7:drop_orders=1") == ("plant:AGV:7", [("drop_orders", "1")])


@pytest.mark.parametrize(
    "spec",
    ["AGV-1", "AGV-1:", ":drop_orders=1", "AGV-1:drop_orders=1,oops", "AGV-1:=3"],
)
def test_malformed_specs_are_refused(spec: str) -> None:
    with pytest.raises(ValueError, match="expected"):
        parse_spec(spec)


def test_every_misbehaviour_from_the_command_line() -> None:
    plan = build_plan(
        [
            "AGV-1:reject_orders=validationError,reject_count=all,delay_orders=2.5",
            "AGV-1:drop_orders=3,duplicate_states=0.5,reorder_states=0.25,stale_states=1",
            "AGV-1:stale_age=90,silent_at=5,silent_for=10,disconnect_at=20,disconnect_for=4",
            "AGV-1:mode=manual,mode_at=30,mode_for=15,fail_actions=pick+drop,fail_count=1",
            "AGV-1:fatal_after_nodes=2,fatal_error=motorFault,seed=9",
        ]
    )
    assert plan == {
        "AGV-1": Misbehaviour(
            reject_orders="validationError",
            reject_count=None,
            delay_orders=2.5,
            drop_orders=3,
            duplicate_states=0.5,
            reorder_states=0.25,
            stale_states=1.0,
            stale_age=90.0,
            silent_at=5.0,
            silent_for=10.0,
            disconnect_at=20.0,
            disconnect_for=4.0,
            mode=OperatingMode.MANUAL,
            mode_at=30.0,
            mode_for=15.0,
            fail_actions=("pick", "drop"),
            fail_count=1,
            fatal_after_nodes=2,
            fatal_error="motorFault",
            seed=9,
        )
    }


def test_keys_are_the_dataclass_fields() -> None:
    assert set(KEYS) == {f.name for f in fields(Misbehaviour)}


@pytest.mark.parametrize(
    ("spec", "message"),
    [
        ("AGV-1:explode=1", "unknown misbehaviour 'explode'"),
        ("AGV-1:drop_orders=1.5", "drop_orders: expected a whole number"),
        ("AGV-1:delay_orders=soon", "could not convert"),
        ("AGV-1:duplicate_states=2", "between 0 and 1"),
        ("AGV-1:mode=FLYING", "unknown operating mode"),
    ],
)
def test_bad_values_are_refused(spec: str, message: str) -> None:
    with pytest.raises(ValueError, match=message):
        build_plan([spec])


def test_script_file_then_flags_later_keys_win(tmp_path: Path) -> None:
    script = tmp_path / "misbehaviour.json"
    script.write_text(
        json.dumps(
            [
                {"serial": "AGV-1", "reject_orders": "orderError", "reject_count": 1},
                {"serial": "AGV-2", "fail_actions": ["pick"], "stale_states": 0.5},
                {"serial": "AGV-1", "reject_count": 2},
            ]
        )
    )
    plan = build_plan(["AGV-2:stale_states=0.1"], script)
    assert plan == {
        "AGV-1": Misbehaviour(reject_orders="orderError", reject_count=2),
        "AGV-2": Misbehaviour(fail_actions=("pick",), stale_states=0.1),
    }


@pytest.mark.parametrize(
    "content",
    ["{not json", '{"serial": "AGV-1"}', '[{"drop_orders": 1}]', '[{"serial": "A", "x": 1}]'],
)
def test_bad_script_files_are_refused(tmp_path: Path, content: str) -> None:
    script = tmp_path / "bad.json"
    script.write_text(content)
    with pytest.raises(ValueError, match="script|serial|unknown"):
        build_plan([], script)


def test_parser_collects_repeated_flags() -> None:
    args = build_parser().parse_args(
        [
            "--count=2",
            "--layout=x.json",
            "--misbehave",
            "AGV-1:drop_orders=1",
            "--misbehave",
            "AGV-2:delay_orders=3",
            "--script",
            "s.json",
        ]
    )
    assert args.misbehave == ["AGV-1:drop_orders=1", "AGV-2:delay_orders=3"]
    assert args.script == "s.json"
    assert build_parser().parse_args(["--count=1", "--layout=x"]).misbehave == []
    assert "reject_orders" in build_parser().format_help()


def _layout_file(tmp_path: Path) -> str:
    path = tmp_path / "layout.json"
    path.write_text(json.dumps(LAYOUT_DICT))
    return str(path)


@pytest.mark.parametrize(
    "extra",
    [
        ["--misbehave", "AGV-1:nonsense=1"],
        ["--misbehave", "AGV-9:drop_orders=1"],  # there is no ninth vehicle
        ["--script", "missing.json"],
    ],
)
def test_main_exits_2_on_bad_misbehaviour(tmp_path: Path, extra: list[str]) -> None:
    with pytest.raises(SystemExit) as exc:
        main(["--count", "2", "--layout", _layout_file(tmp_path), *extra])
    assert exc.value.code == 2


def test_plan_reaches_the_vehicles() -> None:
    plan = {"AGV-2": Misbehaviour(drop_orders=1)}
    vehicles = build_vehicles(
        Layout.from_dict(LAYOUT_DICT), FleetConfig(count=2, misbehaviours=plan)
    )
    assert [v.saboteur.plan for v in vehicles] == [Misbehaviour(), Misbehaviour(drop_orders=1)]
    with pytest.raises(ValueError, match="unknown vehicles"):
        SimulatedFleet(Layout.from_dict(LAYOUT_DICT), FleetConfig(count=1, misbehaviours=plan))


def test_fleet_misbehave_replaces_and_clears() -> None:
    fleet = SimulatedFleet(Layout.from_dict(LAYOUT_DICT), FleetConfig(count=1))  # not started
    applied = fleet.misbehave("AGV-1", reject_orders="orderError", mode="MANUAL")
    assert applied == Misbehaviour(reject_orders="orderError", mode=OperatingMode.MANUAL)
    base = Misbehaviour(drop_orders=2)
    assert fleet.misbehave("AGV-1", base, seed=4) == Misbehaviour(drop_orders=2, seed=4)
    with fleet.vehicle("AGV-1") as vehicle:
        assert vehicle.saboteur.plan == Misbehaviour(drop_orders=2, seed=4)
    fleet.misbehave("AGV-1")
    fleet.set_operating_mode("AGV-1", "SERVICE")
    with fleet.vehicle("AGV-1") as vehicle:
        assert not vehicle.saboteur.plan.active
        assert vehicle.operating_mode is OperatingMode.SERVICE
    fleet.set_silent("AGV-1", duration=2.0)
    with fleet.vehicle("AGV-1") as vehicle:
        assert vehicle.silent
    fleet.set_silent("AGV-1", False)
    with fleet.vehicle("AGV-1") as vehicle:
        assert not vehicle.silent
