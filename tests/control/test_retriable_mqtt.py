"""REFERENCE E.27 end to end: `control` and a simulated 3.0 vehicle over the real Mosquitto.

The vehicle's pick fails (scripted misbehaviour); because control sent it `retriable`, it
enters RETRIABLE and waits. Control retries it up to its limit and then skips it: a pick that
fails once is retried and the order finishes; a pick that always fails is retried twice,
skipped, and the order fails with the reason. Every message control publishes is validated
against the 3.0 schemas.
"""

import time
import uuid

import pytest
from django.conf import settings

from control.controller import Controller
from control.runner import MqttLink
from fleet.mqtt import make_client
from simulator import FleetConfig, Layout, SimulatedFleet
from simulator.misbehaviour import Misbehaviour
from tests.control.fakes import FakeStore, order
from tests.control.test_controller import Published

pytestmark = pytest.mark.e2e

# The same line a-b-c-d (1 m apart, map "demo") as tests.control.fakes.LINE.
LAYOUT = {
    "mapId": "demo",
    "nodes": [{"id": n, "x": float(i), "y": 0.0} for i, n in enumerate("abcd")],
    "edges": [
        {"id": "ab", "start": "a", "end": "b"},
        {"id": "bc", "start": "b", "end": "c"},
        {"id": "cd", "start": "c", "end": "d"},
    ],
    "parking": ["a"],
}


@pytest.mark.parametrize(
    ("fail_count", "ending", "retries", "reason"),
    [
        (1, "finished", ["retry"], None),
        (None, "failed", ["retry", "retry", "skipRetry"], "pick action failed after 2 retries"),
    ],
)
def test_E27_a_failing_pick_is_retried_over_mqtt_then_finishes_or_fails_with_the_reason(
    fail_count, ending, retries, reason
) -> None:
    url = settings.MQTT_URL
    if settings.SERVICES.get("MQTT_URL", "").startswith("embedded"):
        pytest.skip("needs a broker (Mosquitto)")
    interface = f"retry{uuid.uuid4().hex[:8]}"
    controller = Controller(store=FakeStore(), interface_name=interface)
    controller.load()
    controller.fleet.by_pk(1).interface_name = interface  # FakeStore registers it on "uagv"
    client, address = make_client(url, client_id_prefix="test-control")
    link = MqttLink(client, address.host, address.port, controller)
    published = Published()
    published.problems = []

    def publish(topic: str, payload: bytes, qos: int) -> None:
        published(topic, payload, qos)
        link.publish(topic, payload, qos)

    controller.publisher.publish = publish
    plan = Misbehaviour(fail_actions=("pick",), fail_count=fail_count)
    fleet = SimulatedFleet(
        Layout.from_dict(LAYOUT),
        FleetConfig(
            broker_host=address.host,
            broker_port=address.port,
            interface=interface,
            version="3.0.0",
            time_scale=10.0,
            misbehaviours={"AGV-1": plan},
        ),
    )
    link.start()
    fleet.start()
    progress = []
    try:
        assert link.connected.wait(10)
        assert fleet.wait_connected(10)
        vehicle = controller.fleet.by_pk(1)
        deadline = time.monotonic() + 60
        while time.monotonic() < deadline and not {"finished", "failed"} & {
            p.kind for p in progress
        }:
            if vehicle.capabilities is not None:  # the factsheet says it takes retry
                controller.sync([order()])
            controller.flush()
            progress += [p for b in controller.store.batches for p in b.progress]
            controller.store.batches.clear()
            time.sleep(0.1)
    finally:
        fleet.stop()
        link.stop()

    assert published.problems == []
    kinds = [(p.kind, p.detail) for p in progress]
    assert ending in [k for k, _ in kinds], kinds
    sent = [
        (m["actions"][0]["actionType"], m["actions"][0].get("actionParameters"))
        for t, m in published
        if t.endswith("/instantActions")
    ]
    assert [t for t, _ in sent if t in {"retry", "skipRetry"}] == retries
    assert all(p == [{"key": "actionId", "value": "TO-7-pick"}] for t, p in sent if t in retries)
    (order_message, *_) = [m for t, m in published if t.endswith("/order")]
    assert order_message["nodes"][1]["actions"][0]["retriable"] is True
    if reason is not None:
        failed = next(p for p in progress if p.kind == "failed")
        assert failed.detail["reason"].startswith(reason), failed.detail
    assert controller.counters["handler_errors"] == 0
