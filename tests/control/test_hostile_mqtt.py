"""1,000+ malformed, oversized, hostile and mismatched messages over a real broker never stop
`control`: each is rejected and counted (shown in the vehicle's protocol counters, which the
registry stores and alerts report), and the next valid message is applied. Mismatched: a
payload whose serial number differs from its topic's, and 2.x payloads on the 3.0 topic."""

import json
import time
import uuid

import paho.mqtt.client as mqtt
import pytest
from django.conf import settings
from paho.mqtt.enums import CallbackAPIVersion

from control.controller import Controller
from control.runner import MqttLink
from fleet.mqtt import BrokerAddress, make_client
from tests.control.fakes import FakeStore, state

pytestmark = pytest.mark.e2e


def hostile_payloads() -> list[bytes]:
    valid = json.loads(state())
    deep = b"[" * 10_000 + b"]" * 10_000
    return [
        b"",
        b"{",
        b"null",
        b"[]",
        b"\xff\xfe\xfd",
        deep,
        b'{"headerId": NaN}',
        b'{"headerId": Infinity}',
        b'{"headerId": 1e400}',
        b"x" * (2 * 1024 * 1024),
        json.dumps({**valid, "headerId": "seven"}).encode(),
        json.dumps({**valid, "batteryState": None}).encode(),
        json.dumps({**valid, "nodeStates": [{"nodeId": 5}]}).encode(),
        json.dumps({k: v for k, v in valid.items() if k != "orderId"}).encode(),
        json.dumps({**valid, "errors": "none"}).encode(),
    ]


def test_a_flood_of_bad_messages_is_counted_and_the_next_good_one_applies() -> None:
    url = settings.MQTT_URL
    if settings.SERVICES.get("MQTT_URL", "").startswith("embedded"):
        pytest.skip("needs a broker (Mosquitto)")
    interface = f"hostile{uuid.uuid4().hex[:8]}"
    controller = Controller(store=FakeStore(), interface_name=interface)
    controller.load()
    client, address = make_client(url, client_id_prefix="test-control")
    link = MqttLink(client, address.host, address.port, controller)
    link.start()
    attacker = mqtt.Client(callback_api_version=CallbackAPIVersion.VERSION2)
    broker = BrokerAddress.from_url(url)
    attacker.connect(broker.host, broker.port)
    attacker.loop_start()
    try:
        assert link.connected.wait(10)
        topic = f"{interface}/v2/sim/AGV-1/state"
        topic3 = f"{interface}/v3/sim/AGV-1/state"
        sent = 0
        for round_ in range(70):
            for payload in hostile_payloads():
                attacker.publish(topic, payload, qos=1).wait_for_publish(30)
                sent += 1
            attacker.publish(f"{interface}/v2/sim/AGV-{round_}/state", state(serial="EVIL"), qos=1)
            attacker.publish(topic, state(serial="EVIL"), qos=1)  # topic AGV-1, payload EVIL
            sent += 2
            if round_ % 10 == 0:  # version mismatch: 2.x (and garbage) on the 3.0 topic
                for payload in hostile_payloads():
                    attacker.publish(topic3, payload, qos=1).wait_for_publish(30)
                    sent += 1
        attacker.publish(topic, state(header_id=42, last_node="c"), qos=1).wait_for_publish(30)

        deadline = time.monotonic() + 60
        vehicle = controller.fleet.vehicles.get(("sim", "AGV-1"))
        while (vehicle is None or vehicle.state is None) and time.monotonic() < deadline:
            time.sleep(0.1)
            vehicle = controller.fleet.vehicles.get(("sim", "AGV-1"))
    finally:
        attacker.loop_stop()
        attacker.disconnect()
        link.stop()

    assert sent >= 1000
    assert vehicle is not None
    assert vehicle.state is not None
    assert vehicle.state.last_node_id == "c"
    counters = controller.counters
    # Every message that arrived was either rejected and counted or (the last one) applied.
    assert counters["messages"] == counters["decode_errors"] + counters["identity_mismatch"] + 1
    assert counters["decode_errors"] >= 1000
    assert counters["identity_mismatch"] >= 1
    assert controller.counters["handler_errors"] == 0
    assert set(controller.fleet.vehicles) == {("sim", "AGV-1")}
    # Shown: the vehicle's protocol counters go to the registry with its next snapshot.
    controller.flush()
    (row,) = [r for b in controller.store.batches for r in b.snapshots if r["pk"] == 1]
    assert row["protocol_counters"]["decode_errors"] >= 1000
    assert row["protocol_counters"]["identity_mismatch"] >= 70
    print(f"hostile: {sent} bad messages rejected, counters {dict(controller.counters)}")
