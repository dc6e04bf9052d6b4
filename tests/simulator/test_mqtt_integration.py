"""Integration tests against the real Mosquitto on 127.0.0.1:1883.

Each test uses its own interface name (``simtest<random>``) so runs never see each other's
retained messages, and clears the retained topics it created afterwards.
"""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
from pathlib import Path

from simulator import FleetConfig, Layout, SimulatedFleet
from tests.simulator.builders import LAYOUT_DICT, action, instant, make_order
from tests.simulator.recorder import HOST, PORT, Recorder, connection, needs_broker
from vda5050 import encode
from vda5050.enums import ErrorLevel

ROOT = Path(__file__).resolve().parents[2]

pytestmark = needs_broker


def test_fleet_end_to_end(recorder: Recorder) -> None:
    config = FleetConfig(
        count=2, interface=recorder.interface, time_scale=10.0, visualization_hz=5.0
    )
    fleet = SimulatedFleet(Layout.from_dict(LAYOUT_DICT), config)
    fleet.start()
    try:
        assert fleet.wait_connected(10.0)
        recorder.subscribe()  # after connecting: factsheet and ONLINE must come retained
        for serial in ("AGV-1", "AGV-2"):
            online = recorder.wait_for(connection(serial, "ONLINE"))
            assert online.retain
            sheet = recorder.wait_for(lambda m, s=serial: m.serial == s and m.kind == "factsheet")
            assert sheet.retain
            assert sheet.data["serialNumber"] == serial
        recorder.wait_for(lambda m: m.serial == "AGV-2" and m.kind == "visualization")

        pick = action("pick", "p1", loadId="L7", loadType="EPAL")
        order = make_order("o-int", ["n1", "n2", "n3"], actions={"n2": [pick]})
        recorder.publish("AGV-1", "order", encode(order))
        recorder.wait_for(
            lambda m: m.kind == "state" and m.serial == "AGV-1" and m.data["orderId"] == "o-int"
        )
        done = recorder.wait_for(
            lambda m: (
                m.kind == "state"
                and m.serial == "AGV-1"
                and m.data["orderId"] == "o-int"
                and m.data["nodeStates"] == []
                and m.data["lastNodeId"] == "n3"
            ),
            timeout=15.0,
        )
        assert [a["actionStatus"] for a in done.data["actionStates"]] == ["FINISHED"]
        assert done.data["loads"] == [{"loadId": "L7", "loadType": "EPAL"}]
        assert done.data["agvPosition"]["x"] == 10.0
        states = [m.data for m in recorder.messages if m.kind == "state" and m.serial == "AGV-1"]
        header_ids = [s["headerId"] for s in states]
        assert header_ids == sorted(header_ids)
        assert len(set(header_ids)) == len(header_ids)

        # An order that does not even decode is reported as a validationError.
        recorder.publish("AGV-2", "order", b'{"orderId": 42}')
        recorder.wait_for(
            lambda m: (
                m.kind == "state"
                and m.serial == "AGV-2"
                and [e["errorType"] for e in m.data["errors"]] == ["validationError"]
            )
        )
        # Instant actions over MQTT: cancelOrder without an order fails.
        recorder.publish("AGV-2", "instantActions", encode(instant(action("cancelOrder", "c9"))))
        recorder.wait_for(
            lambda m: (
                m.kind == "state"
                and m.serial == "AGV-2"
                and any(
                    a["actionId"] == "c9" and a["actionStatus"] == "FAILED"
                    for a in m.data["actionStates"]
                )
            )
        )
        # Fault injection shows up in the next state right away.
        fleet.inject_error("AGV-1", "injectedFault", ErrorLevel.FATAL)
        recorder.wait_for(
            lambda m: (
                m.kind == "state"
                and m.serial == "AGV-1"
                and {"errorType": "injectedFault", "errorLevel": "FATAL"} in m.data["errors"]
            )
        )
    finally:
        fleet.stop()
    for serial in ("AGV-1", "AGV-2"):
        recorder.wait_for(connection(serial, "OFFLINE"))


def test_broken_connection_sends_last_will_and_reconnects(recorder: Recorder) -> None:
    config = FleetConfig(count=1, interface=recorder.interface, visualization_hz=0.0)
    fleet = SimulatedFleet(Layout.from_dict(LAYOUT_DICT), config)
    recorder.subscribe()
    fleet.start()
    try:
        first = recorder.wait_for(connection("AGV-1", "ONLINE"))
        fleet.break_connection("AGV-1")
        recorder.wait_for(connection("AGV-1", "CONNECTIONBROKEN"))
        again = recorder.wait_for(
            lambda m: connection("AGV-1", "ONLINE")(m) and m is not first, timeout=15.0
        )
        assert again.data["headerId"] > first.data["headerId"]
    finally:
        fleet.stop()
    recorder.wait_for(connection("AGV-1", "OFFLINE"))


def test_cli_stops_cleanly_on_sigterm(recorder: Recorder, tmp_path: Path) -> None:
    layout = tmp_path / "layout.json"
    layout.write_text(json.dumps(LAYOUT_DICT))
    recorder.subscribe()
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    command = [
        sys.executable,
        "-m",
        "simulator",
        "--count",
        "2",
        "--layout",
        str(layout),
        "--broker",
        f"mqtt://{HOST}:{PORT}",
        "--interface",
        recorder.interface,
        "--visualization-hz",
        "0",
    ]
    proc = subprocess.Popen(
        command, cwd=ROOT, env=env, stdout=subprocess.PIPE, stderr=subprocess.STDOUT
    )
    try:
        for serial in ("AGV-1", "AGV-2"):
            recorder.wait_for(connection(serial, "ONLINE"), timeout=15.0)
        proc.send_signal(signal.SIGTERM)
        output, _ = proc.communicate(timeout=15)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()
    assert proc.returncode == 0, output.decode(errors="replace")
    for serial in ("AGV-1", "AGV-2"):
        recorder.wait_for(connection(serial, "OFFLINE"))
    broken = [m for m in recorder.messages if m.data.get("connectionState") == "CONNECTIONBROKEN"]
    assert broken == []
