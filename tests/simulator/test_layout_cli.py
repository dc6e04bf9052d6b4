"""Layout parsing, fleet construction, CLI arguments and MQTT helpers (no broker needed)."""

from __future__ import annotations

import json
import math
from pathlib import Path

import pytest

from simulator.__main__ import build_parser, main, parse_broker
from simulator.fleet import FleetConfig, build_vehicles
from simulator.layout import Layout, LayoutError, load_layout
from simulator.mqtt import _guarded
from tests.simulator.builders import LAYOUT_DICT


def test_vehicles_start_on_parking_spots_round_robin() -> None:
    layout = Layout.from_dict(LAYOUT_DICT)
    vehicles = build_vehicles(layout, FleetConfig(count=3, serial_prefix="SIM-"))
    assert [v.config.serial_number for v in vehicles] == ["SIM-1", "SIM-2", "SIM-3"]
    assert [v.last_node_id for v in vehicles] == ["n1", "n3", "n1"]
    assert [(v.x, v.y) for v in vehicles] == [(0.0, 0.0), (10.0, 0.0), (0.0, 0.0)]
    assert all(v.position_initialized for v in vehicles)
    assert vehicles[1].theta == pytest.approx(math.pi / 2)  # facing along its first edge


def test_vehicles_start_on_nodes_without_parking() -> None:
    layout = Layout.from_dict({**LAYOUT_DICT, "parking": []})
    vehicles = build_vehicles(layout, FleetConfig(count=2))
    assert [v.last_node_id for v in vehicles] == ["n1", "n2"]


@pytest.mark.parametrize(
    "data",
    [
        {"nodes": [{"id": "a", "x": 0, "y": 0}]},
        {"mapId": "m", "nodes": []},
        {"mapId": "m", "nodes": [{"id": "a", "x": "left", "y": 0}]},
        {"mapId": "m", "nodes": [{"id": "a", "x": 0, "y": 0}], "parking": ["b"]},
    ],
)
def test_bad_layouts_are_rejected(data: dict[str, object]) -> None:
    with pytest.raises(LayoutError):
        Layout.from_dict(data)


def test_load_layout_from_file(tmp_path: Path) -> None:
    path = tmp_path / "layout.json"
    path.write_text(json.dumps(LAYOUT_DICT))
    assert load_layout(path).map_id == "demo"
    with pytest.raises(LayoutError):
        load_layout(tmp_path / "missing.json")


def test_parse_broker() -> None:
    assert parse_broker("mqtt://127.0.0.1:1883") == ("127.0.0.1", 1883, None, None)
    assert parse_broker("mqtt://u:p%40ss@broker") == ("broker", 1883, "u", "p@ss")
    assert parse_broker("localhost:1884") == ("localhost", 1884, None, None)
    with pytest.raises(ValueError, match="scheme"):
        parse_broker("http://x")


def test_cli_defaults_and_units() -> None:
    args = build_parser().parse_args(["--count", "2", "--layout", "x.json", "--speed", "1.5 m/s"])
    assert (args.speed, args.version, args.interface, args.state_interval) == (
        1.5,
        "2.0.0",
        "uagv",
        30.0,
    )


def test_cli_accepts_every_version_it_speaks() -> None:
    for version in ("2.0.0", "2.1.0", "3.0.0"):
        args = build_parser().parse_args(["--count", "1", "--layout", "x", "--version", version])
        assert args.version == version


def test_cli_rejects_bad_input(tmp_path: Path) -> None:
    with pytest.raises(SystemExit) as exc:
        main(["--count", "1", "--layout", str(tmp_path / "missing.json")])
    assert exc.value.code == 2
    with pytest.raises(SystemExit):
        main(["--count", "1", "--layout", "x.json", "--version", "1.1.0"])
    path = tmp_path / "layout.json"
    path.write_text(json.dumps(LAYOUT_DICT))
    with pytest.raises(SystemExit) as exc:
        main(["--count", "1", "--layout", str(path), "--serial-prefix", "bad/"])
    assert exc.value.code == 2


def test_callback_exceptions_are_logged_not_raised(caplog: pytest.LogCaptureFixture) -> None:
    def boom(*_args: object) -> None:
        raise RuntimeError("bad vehicle")

    _guarded("message", boom)(None, None, None)
    assert "error in MQTT message callback" in caplog.text
