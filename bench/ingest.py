"""Ingest cost of `control`'s hot path, in process (no broker): µs per state message.

Compares, in one run, the bare msgspec decode of a realistic state message (the floor) with
`Controller.handle_message` (topic parse, decode, live-model update, order tracking, dirty
marking), and the flush/broadcast collection that runs once per interval. The DESIGN budget is
~45 µs per message for paho + decode; the ratio says what our handling adds on top of decoding.
"""

import argparse
import time
from typing import Any

import vda5050
from bench import results
from control.controller import Controller
from control.execution import LayoutIndex, NodePlace
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


def measure(vehicles: int, messages: int) -> dict[str, float]:
    payloads = [
        (f"uagv/v2/bench/AGV-{i}/state", state_message(f"AGV-{i}", i)) for i in range(vehicles)
    ]
    controller = Controller(store=NullStore(), interface_name="uagv")
    controller.load()
    for topic, payload in payloads:  # register every vehicle, then give each an order to track
        controller.handle_message(topic, payload)
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

    start = time.perf_counter()
    for n in range(messages):
        vda5050.decode(vda5050.TopicKind.STATE, payloads[n % vehicles][1])
    decode_us = (time.perf_counter() - start) / messages * 1e6

    start = time.perf_counter()
    for n in range(messages):
        topic, payload = payloads[n % vehicles]
        controller.handle_message(topic, payload)
    handle_us = (time.perf_counter() - start) / messages * 1e6

    start = time.perf_counter()
    controller.collect_flush()
    rows = controller.collect_broadcast()
    collect_ms = (time.perf_counter() - start) * 1e3
    assert len(rows) == vehicles
    assert controller.counters["decode_errors"] == 0
    return {
        "decode_us_per_msg": decode_us,
        "handle_us_per_msg": handle_us,
        "handle_to_decode_ratio": handle_us / decode_us,
        "messages_per_core_second": 1e6 / handle_us,
        "flush_and_broadcast_collect_ms": collect_ms,
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--quick", action="store_true")
    parser.add_argument("--vehicles", type=int, default=1000)
    args = parser.parse_args()
    messages = 20_000 if args.quick else 200_000
    figures = measure(args.vehicles, messages)
    print(f"ingest: {args.vehicles} vehicles, {messages} state messages, in process")
    print(f"  msgspec decode only        {figures['decode_us_per_msg']:7.1f} µs/msg")
    print(
        f"  Controller.handle_message  {figures['handle_us_per_msg']:7.1f} µs/msg "
        f"({figures['handle_to_decode_ratio']:.2f}× decode, "
        f"{figures['messages_per_core_second']:,.0f} msg/s per core)"
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
