"""The fuzzing harness of control's inbound path (`bench.fuzz`): its seeds go through control
without a handler error, and a short coverage-guided run finds no crash."""

import json
import subprocess
import sys
from pathlib import Path

import pytest

from bench.fuzz import SERIALS, seeds, topic_of
from bench.traffic_control import Store, layout_index
from control.controller import Controller
from maps.demo import warehouse_layout


def test_every_seed_is_handled_and_the_valid_ones_apply() -> None:
    layout, _ = layout_index(warehouse_layout(columns=4, rows=3))
    controller = Controller(
        store=Store(layout, list(SERIALS[:3])),
        interface_name="uagv",
        publish=lambda topic, payload, qos: None,
    )
    controller.load()
    inputs = seeds()
    for data in inputs:
        controller.handle_message(*topic_of(data))

    assert controller.counters["handler_errors"] == 0
    assert controller.counters["messages"] == len(inputs)
    assert controller.counters["decode_errors"] >= 250  # the hostile states
    versions = {v.serial_number: v.version for v in controller.fleet.vehicles.values()}
    assert versions == {"AGV-1": "2.0.0", "AGV-2": "2.1.0", "AGV-3": "3.0.0"}
    assert all(v.factsheet is not None for v in controller.fleet.vehicles.values())


@pytest.mark.e2e
def test_a_short_fuzzing_run_finds_no_crash(tmp_path: Path) -> None:
    out = tmp_path / "fuzz.json"
    result = subprocess.run(
        [sys.executable, "-m", "bench.fuzz", "--seconds", "15", "--json", str(out)],
        capture_output=True,
        text=True,
        timeout=300,
        check=False,
    )
    assert result.returncode == 0, result.stdout[-3000:] + result.stderr[-3000:]
    figures = json.loads(out.read_text())
    assert figures["crashes"] == []
    assert figures["runs"] > 1_000
    assert figures["coverage_edges"] > 0


def test_a_malformed_header_version_is_refused_and_the_vehicle_goes_on() -> None:
    """Found by the fuzzer: a state whose header said version "ac2.0.1" was applied, kept as
    the vehicle's version, and every later message of the vehicle raised."""
    layout, _ = layout_index(warehouse_layout(columns=4, rows=3))
    controller = Controller(store=Store(layout, ["AGV-1"]), interface_name="uagv")
    controller.load()
    valid = json.loads(topic_of(seeds()[0])[1])
    topic = "uagv/v2/sim/AGV-1/state"
    controller.handle_message(topic, json.dumps(valid | {"version": "ac2.0.1"}).encode())
    controller.handle_message(topic, json.dumps(valid | {"headerId": 5}).encode())

    assert controller.counters["decode_errors"] == 1
    vehicle = controller.fleet.vehicles[("sim", "AGV-1")]
    assert vehicle.version == "2.0.0"
    assert vehicle.state is not None
    assert vehicle.state.header_id == 5


def test_a_malformed_version_stored_earlier_does_not_stop_the_vehicle() -> None:
    from control.versions import wire_version

    assert wire_version("v2", "ac2.0.1") == "2.0.0"
    assert wire_version("v3", "garbage") == "3.0.0"
    assert wire_version("v2", "2.1.0") == "2.1.0"
