"""Misbehaviour seen by a real subscriber on the Mosquitto at 127.0.0.1:1883."""

from __future__ import annotations

import json
import os
import subprocess
import sys
import time
from pathlib import Path

from simulator import FleetConfig, Layout, Misbehaviour, SimulatedFleet
from tests.simulator.builders import LAYOUT_DICT, make_order
from tests.simulator.recorder import HOST, PORT, Received, Recorder, connection, needs_broker
from vda5050 import encode

pytestmark = needs_broker

ROOT = Path(__file__).resolve().parents[2]


def _states(recorder: Recorder, serial: str) -> list[dict[str, object]]:
    with recorder._cond:
        return [m.data for m in recorder.messages if m.kind == "state" and m.serial == serial]


def _rejected(order_id: str, serial: str = "AGV-2") -> object:
    def match(m: Received) -> bool:
        return (
            m.kind == "state"
            and m.serial == serial
            and any(
                e["errorType"] == "orderError"
                and e["errorLevel"] == "WARNING"
                and {"referenceKey": "orderId", "referenceValue": order_id}
                in e.get("errorReferences", [])
                for e in m.data["errors"]
            )
        )

    return match


def test_duplicate_and_reordered_states_and_a_rejection_reach_the_subscriber(
    recorder: Recorder,
) -> None:
    plan = {
        "AGV-1": Misbehaviour(duplicate_states=1.0),
        "AGV-2": Misbehaviour(reorder_states=1.0, reject_orders="orderError", reject_count=1),
    }
    config = FleetConfig(
        count=2, interface=recorder.interface, visualization_hz=0.0, misbehaviours=plan
    )
    fleet = SimulatedFleet(Layout.from_dict(LAYOUT_DICT), config)
    recorder.subscribe()
    fleet.start()
    try:
        assert fleet.wait_connected(10.0)
        recorder.publish("AGV-2", "order", encode(make_order("o-bad", ["n3", "n4"])))
        recorder.wait_for(_rejected("o-bad"))  # type: ignore[arg-type]
        recorder.publish("AGV-2", "order", encode(make_order("o-good", ["n3", "n4"])))
        recorder.wait_for(
            lambda m: m.serial == "AGV-2" and m.kind == "state" and m.data["orderId"] == "o-good"
        )
        recorder.publish("AGV-1", "order", encode(make_order("o-1", ["n1", "n2"])))
        recorder.wait_for(
            lambda m: m.serial == "AGV-1" and m.kind == "state" and m.data["orderId"] == "o-1"
        )
        time.sleep(0.5)  # let the held-back / duplicate copies arrive too
    finally:
        fleet.stop()
    ids_1 = [s["headerId"] for s in _states(recorder, "AGV-1")]
    assert len(ids_1) >= 4
    assert ids_1[0::2] == ids_1[1::2]  # every state twice in a row, same headerId
    ids_2 = [s["headerId"] for s in _states(recorder, "AGV-2")]
    assert any(later < earlier for earlier, later in zip(ids_2, ids_2[1:], strict=False))
    assert sorted(ids_2) == list(range(len(ids_2)))  # nothing lost, only reordered


def test_cli_script_and_timed_disconnect(recorder: Recorder, tmp_path: Path) -> None:
    layout = tmp_path / "layout.json"
    layout.write_text(json.dumps(LAYOUT_DICT))
    script = tmp_path / "script.json"
    script.write_text(json.dumps([{"serial": "AGV-2", "disconnect_at": 1, "disconnect_for": 3}]))
    recorder.subscribe()
    command = [
        sys.executable,
        "-m",
        "simulator",
        *("--count", "2", "--layout", str(layout), "--interface", recorder.interface),
        *("--broker", f"mqtt://{HOST}:{PORT}", "--visualization-hz", "0"),
        *("--script", str(script), "--misbehave", "AGV-1:reject_orders=orderError"),
    ]
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    proc = subprocess.Popen(
        command, cwd=ROOT, env=env, stdout=subprocess.PIPE, stderr=subprocess.STDOUT
    )
    try:
        recorder.wait_for(connection("AGV-1", "ONLINE"), timeout=15.0)
        recorder.publish("AGV-1", "order", encode(make_order("o-cli", ["n1", "n2"])))
        rejected = recorder.wait_for(_rejected("o-cli", "AGV-1"))  # type: ignore[arg-type]
        assert rejected.data["orderId"] == ""
        broken = recorder.wait_for(connection("AGV-2", "CONNECTIONBROKEN"), timeout=10.0)
        online_again = recorder.wait_for(
            lambda m: connection("AGV-2", "ONLINE")(m) and m.at > broken.at, timeout=15.0
        )
        assert online_again.at - broken.at >= 2.5  # stayed away for the scripted 3 s
        assert online_again.data["headerId"] >= 2  # will = 0, first ONLINE = 1
    finally:
        proc.terminate()
        output, _ = proc.communicate(timeout=15)
    text = output.decode(errors="replace")
    assert proc.returncode == 0, text
    assert "misbehaviour disconnect: dropping the connection for 3 s" in text
    assert "misbehaviour reject_orders: rejecting order o-cli/0 with orderError" in text
