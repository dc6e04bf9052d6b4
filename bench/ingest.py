"""Ingest cost of `control`'s hot path, in process (no broker): µs per state message.

Compares, in one run, the bare msgspec decode of a realistic state message (the floor) with
`Controller.handle_message` (topic parse, decode, live-model update, order tracking, dirty
marking), and the flush/broadcast collection that runs once per interval. The DESIGN budget is
~45 µs per message for paho + decode; the ratio says what our handling adds on top of decoding.
Visualization messages (up to 10 a second per vehicle, control keeps only the position) are
measured the same way, and the share of one core that issue 11's load takes (2,000 states and
1,000 visualizations a second, through the paho callback) is derived from both.
"""

import argparse
import os
import time
from collections.abc import Callable
from typing import Any

import paho.mqtt.client as mqtt
from paho.mqtt.enums import CallbackAPIVersion

import vda5050
from bench import results
from control.controller import Controller
from control.execution import LayoutIndex, NodePlace
from control.metrics import ControlMetrics
from control.ports import ActiveOrder, FlushBatch

NODES = [f"n{i}" for i in range(20)]
LAYOUT = LayoutIndex(
    "bench",
    {n: NodePlace(float(i), 0.0, None, "bench") for i, n in enumerate(NODES)},
    {(a, b): f"{a}-{b}" for a, b in zip(NODES, NODES[1:], strict=False)},
)


class NullStore:
    def load_layouts(self) -> dict[str, LayoutIndex]:
        return {"bench": LAYOUT}

    def load_vehicles(self) -> list[dict[str, Any]]:
        return []

    def active_orders(self) -> list[ActiveOrder]:
        return []

    def flush(self, batch: FlushBatch) -> dict[tuple[str, str], int]:
        return {v.key: i for i, v in enumerate(batch.new_vehicles)}

    def vehicle_dialects(self) -> dict[int, str]:
        return {}

    def layouts_revision(self) -> object:
        return 0

    def request_dispatch(self) -> None:
        return None


def state_message(serial: str, header_id: int) -> bytes:
    """A driving vehicle's state with 10 nodes ahead, two actions and a load."""
    ahead = NODES[5:15]
    message = vda5050.State(
        header_id=header_id,
        timestamp=vda5050.now_timestamp("2.0.0"),
        version="2.0.0",
        manufacturer="bench",
        serial_number=serial,
        order_id="TO-1",
        order_update_id=0,
        last_node_id="n4",
        last_node_sequence_id=8,
        driving=True,
        operating_mode=vda5050.OperatingMode.AUTOMATIC,
        node_states=[
            vda5050.NodeState(node_id=n, sequence_id=10 + 2 * i, released=True)
            for i, n in enumerate(ahead)
        ],
        edge_states=[
            vda5050.EdgeState(edge_id=f"e{i}", sequence_id=9 + 2 * i, released=True)
            for i, _ in enumerate(ahead)
        ],
        action_states=[
            vda5050.ActionState(action_id=a, action_status=vda5050.ActionStatus.WAITING)
            for a in ("TO-1-pick", "TO-1-drop")
        ],
        battery_state=vda5050.BatteryState(battery_charge=71.5, charging=False),
        errors=[],
        loads=[vda5050.Load(load_id="L1", load_type="EPAL")],
        safety_state=vda5050.SafetyState(e_stop=vda5050.EStop.NONE, field_violation=False),
        agv_position=vda5050.AgvPosition(
            x=4.2, y=0.0, theta=0.0, map_id="bench", position_initialized=True
        ),
    )
    return vda5050.encode(message)


def visualization_message(serial: str, header_id: int) -> bytes:
    """A moving vehicle's visualization: position and velocity."""
    message = vda5050.Visualization(
        header_id=header_id,
        timestamp=vda5050.now_timestamp("2.0.0"),
        version="2.0.0",
        manufacturer="bench",
        serial_number=serial,
        agv_position=vda5050.AgvPosition(
            x=4.2, y=0.5, theta=1.57, map_id="bench", position_initialized=True
        ),
        velocity=vda5050.Velocity(vx=1.0, vy=0.0, omega=0.1),
    )
    return vda5050.encode(message)


def _link(controller: Controller) -> Callable[[mqtt.MQTTMessage], None]:
    """control's real inbound path without a socket: paho's callback as `MqttLink` sets it,
    wrapped by `ControlMetrics` (counting and timing) exactly as `control.service` does."""
    import django

    os.environ.setdefault("DJANGO_SETTINGS_MODULE", "fleet.settings")
    django.setup()  # control.runner imports the map store (models); nothing touches the DB
    from control.runner import MqttLink

    client = mqtt.Client(CallbackAPIVersion.VERSION2)
    link = MqttLink(client, "localhost", 1883, controller)
    controller.publisher.publish = lambda topic, payload, qos: None  # no socket: discarded
    ControlMetrics(controller).instrument(link)
    on_message = client.on_message
    assert on_message is not None
    return lambda message: on_message(client, None, message)


def _message(topic: str, payload: bytes) -> mqtt.MQTTMessage:
    message = mqtt.MQTTMessage(topic=topic.encode())
    message.payload = payload
    return message


def measure(vehicles: int, messages: int) -> dict[str, float]:
    """CPU time (not wall clock: the machine is shared) per message. Every round sends each
    vehicle its next state (a new header id), so each message is applied, not dropped as a
    duplicate."""
    topics = [f"uagv/v2/bench/AGV-{i}/state" for i in range(vehicles)]
    controller = Controller(store=NullStore(), interface_name="uagv")
    controller.live_page_open = lambda: True  # rows as with a page open
    controller.load()
    deliver = _link(controller)
    for i, topic in enumerate(topics):  # register every vehicle, then give each an order to track
        controller.handle_message(topic, state_message(f"AGV-{i}", 1))
    controller.flush()
    controller.sync(
        [
            ActiveOrder(
                transport_order_id=v.pk,
                vda_order_id="TO-1",
                vehicle_pk=v.pk,
                route=NODES,
                pickup_node="n2",
                map_id="bench",
                pick_station="P",
                drop_station="D",
            )
            for v in controller.fleet.vehicles.values()
            if v.pk is not None
        ]
    )
    assert all(v.execution is not None for v in controller.fleet.vehicles.values())

    decode_s = handle_s = link_s = 0.0
    viz_decode_s = viz_handle_s = viz_link_s = 0.0
    viz_topics = [f"uagv/v2/bench/AGV-{i}/visualization" for i in range(vehicles)]
    rounds = max(1, messages // vehicles // 2)  # half directly, half through the link
    header_id = 1
    for _round in range(rounds):
        header_id += 1
        payloads = [state_message(f"AGV-{i}", header_id) for i in range(vehicles)]
        start = time.process_time()
        for payload in payloads:
            vda5050.decode(vda5050.TopicKind.STATE, payload)
        decode_s += time.process_time() - start
        start = time.process_time()
        for topic, payload in zip(topics, payloads, strict=True):
            controller.handle_message(topic, payload)
        handle_s += time.process_time() - start
        header_id += 1  # the same through the paho callback and the metrics wrapper
        wrapped = [
            _message(topic, state_message(f"AGV-{i}", header_id)) for i, topic in enumerate(topics)
        ]
        start = time.process_time()
        for message in wrapped:
            deliver(message)
        link_s += time.process_time() - start
        # Visualizations have header ids of their own: the same numbering works.
        visuals = [visualization_message(f"AGV-{i}", header_id) for i in range(vehicles)]
        start = time.process_time()
        for payload in visuals:
            vda5050.decode(vda5050.TopicKind.VISUALIZATION, payload)
        viz_decode_s += time.process_time() - start
        start = time.process_time()
        for topic, payload in zip(viz_topics, visuals, strict=True):
            controller.handle_message(topic, payload)
        viz_handle_s += time.process_time() - start
        wrapped = [
            _message(topic, visualization_message(f"AGV-{i}", header_id + 1))
            for i, topic in enumerate(viz_topics)
        ]
        start = time.process_time()
        for message in wrapped:
            deliver(message)
        viz_link_s += time.process_time() - start
    count = rounds * vehicles
    applied = controller.counters
    assert applied["duplicate"] == 0, dict(applied)
    assert applied["stale"] == 0, dict(applied)

    start = time.process_time()
    controller.collect_flush()
    rows = controller.collect_broadcast()
    collect_ms = (time.process_time() - start) * 1e3
    assert len(rows) == vehicles
    assert controller.counters["decode_errors"] == 0
    decode_us, handle_us, link_us = (t / count * 1e6 for t in (decode_s, handle_s, link_s))
    viz_decode_us, viz_handle_us, viz_link_us = (
        t / count * 1e6 for t in (viz_decode_s, viz_handle_s, viz_link_s)
    )
    return {
        "decode_us_per_msg": decode_us,
        "handle_us_per_msg": handle_us,
        "link_us_per_msg": link_us,
        "handle_to_decode_ratio": handle_us / decode_us,
        "messages_per_core_second": 1e6 / link_us,
        "flush_and_broadcast_collect_ms": collect_ms,
        "visualization_decode_us_per_msg": viz_decode_us,
        "visualization_handle_us_per_msg": viz_handle_us,
        "visualization_link_us_per_msg": viz_link_us,
        # issue 11's load: 2,000 states and 1,000 visualizations a second (target <= 25 %)
        "issue11_core_percent": (2000 * link_us + 1000 * viz_link_us) / 1e6 * 100,
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--quick", action="store_true")
    parser.add_argument("--vehicles", type=int, default=1000)
    args = parser.parse_args()
    messages = 20_000 if args.quick else 200_000
    figures = measure(args.vehicles, messages)
    print(f"ingest: {args.vehicles} vehicles, {messages} state messages, in process (CPU time)")
    print(f"  msgspec decode only        {figures['decode_us_per_msg']:7.1f} µs/msg")
    print(
        f"  Controller.handle_message  {figures['handle_us_per_msg']:7.1f} µs/msg "
        f"({figures['handle_to_decode_ratio']:.2f}× decode)"
    )
    print(
        f"  + paho callback, metrics   {figures['link_us_per_msg']:7.1f} µs/msg "
        f"({figures['messages_per_core_second']:,.0f} msg/s per core, CPU time)"
    )
    print(
        f"  visualization: decode      {figures['visualization_decode_us_per_msg']:7.1f} µs/msg, "
        f"handle_message {figures['visualization_handle_us_per_msg']:.1f}, "
        f"+ paho, metrics {figures['visualization_link_us_per_msg']:.1f}"
    )
    print(
        f"  2,000 states/s + 1,000 visualizations/s: {figures['issue11_core_percent']:.1f} % "
        "of one core (CPU time, target <= 25 %)"
    )
    print(
        f"  flush+broadcast collection {figures['flush_and_broadcast_collect_ms']:7.1f} ms "
        f"for {args.vehicles} dirty vehicles"
    )
    path = results.write(
        "ingest", {**figures, "vehicles": args.vehicles, "messages": messages, "quick": args.quick}
    )
    print(f"  written to {path.relative_to(path.parents[2])}")


if __name__ == "__main__":
    main()
