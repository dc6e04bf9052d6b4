"""Traffic management inside `control`, in process: release decision time per state message.

A warehouse of `maps.demo` (aisles, pick and drop stations on spurs) with in-process simulated
vehicles (`simulator.VirtualVehicle`, no broker) wired to a `Controller` with traffic management
on. Each idle vehicle gets a transport order from its spur through a free pick spur to a free drop
spur; a share of moves is delayed. Reports the traffic link's decision time per state message
(`TrafficLink.observe`: progress, clearing, base releases of this and waiting vehicles), the whole
`handle_message` time, orders finished, and the simulator's collision count (must be 0).

    .venv/bin/python -m bench.traffic_control --vehicles 14 --seconds 600
"""

import argparse
import math
import random
import statistics
import time
from typing import Any

import vda5050
from bench import results
from control.controller import Controller
from control.execution import LayoutIndex, NodePlace
from control.ports import ActiveOrder, FlushBatch
from maps.demo import warehouse_layout
from simulator import wire
from simulator.collisions import Body, CollisionChecker
from simulator.config import StartPose, VehicleConfig
from simulator.delays import DelayConfig, DelayInjector
from simulator.fleet import footprint_of
from simulator.vehicle import VirtualVehicle
from vda5050.enums import ConnectionState, TopicKind


def layout_index(spec: dict[str, Any]) -> tuple[LayoutIndex, list[str]]:
    """The control layout of a demo warehouse spec and its pick/drop spur nodes."""
    nodes = {n["id"]: NodePlace(n["x"], n["y"], None, spec["mapId"]) for n in spec["nodes"]}
    edges = {(e["start"], e["end"]): e["id"] for e in spec["edges"]}
    spurs = [s["node"] for s in spec["stations"] if s["kind"] in {"PICK", "DROP"}]
    return LayoutIndex(spec["mapId"], nodes, edges), spurs


class Store:
    def __init__(self, layout: LayoutIndex, serials: list[str]) -> None:
        self.layout, self.serials = layout, serials

    def load_layouts(self) -> dict[str, LayoutIndex]:
        return {self.layout.map_id: self.layout}

    def load_vehicles(self) -> list[dict[str, Any]]:
        return [
            {
                "pk": i + 1,
                "manufacturer": "sim",
                "serial_number": s,
                "interface_name": "uagv",
                "protocol_version": "2.0.0",
            }
            for i, s in enumerate(self.serials)
        ]

    def active_orders(self) -> list[ActiveOrder]:
        return []

    def flush(self, batch: FlushBatch) -> dict[tuple[str, str], int]:
        return {}

    def vehicle_dialects(self) -> dict[int, str]:
        return {}

    def layouts_revision(self) -> object:
        return 0

    def request_dispatch(self) -> None:
        return None


def percentile(samples: list[float], q: float) -> float:
    ordered = sorted(samples)
    return ordered[min(len(ordered) - 1, int(q * len(ordered)))] if ordered else math.nan


def measure(vehicles: int, seconds: float, columns: int, delay_share: float) -> dict[str, Any]:
    spec = warehouse_layout(columns=columns, rows=6, map_id="bench")
    layout, spurs = layout_index(spec)
    rng = random.Random(5)
    homes = rng.sample(spurs, vehicles)
    serials = [f"AGV-{i + 1}" for i in range(vehicles)]
    known = {n: (p.x, p.y) for n, p in layout.nodes.items()}
    fleet: dict[str, VirtualVehicle] = {}
    for i, (serial, home) in enumerate(zip(serials, homes, strict=True)):
        place = layout.nodes[home]
        vehicle = VirtualVehicle(
            VehicleConfig(serial_number=serial, state_interval=1.0),
            StartPose("bench", home, place.x, place.y, 0.0),
            known_nodes=known,
        )
        vehicle.delays = DelayInjector(DelayConfig(share=delay_share, seed=9), stream=i)
        fleet[serial] = vehicle

    def deliver(topic: str, payload: bytes, qos: int) -> None:
        serial, kind = topic.split("/")[-2:]
        if kind == "order":
            fleet[serial].on_order(wire.decode_inbound(TopicKind.ORDER, payload, "2.0.0"))  # type: ignore[arg-type]
        elif kind == "instantActions":
            message = wire.decode_inbound(TopicKind.INSTANT_ACTIONS, payload, "2.0.0")
            fleet[serial].on_instant_actions(message)  # type: ignore[arg-type]

    controller = Controller(
        store=Store(layout, serials), interface_name="uagv", publish=deliver, traffic=True
    )
    controller.load()
    traffic = controller.traffic
    assert traffic is not None
    handle: list[float] = []
    # CPU time of each decision as well: on a loaded 2-core machine wall-clock outliers are
    # mostly time spent descheduled, not work.
    cpu: list[float] = []
    observe = traffic.observe

    def timed_observe(*args: Any) -> Any:
        started = time.thread_time()
        try:
            return observe(*args)
        finally:
            cpu.append(time.thread_time() - started)

    traffic.observe = timed_observe  # type: ignore[method-assign,assignment]

    def publish_state(serial: str) -> None:
        for state in wire.states(fleet[serial]):
            payload = vda5050.encode(state)
            started = time.perf_counter()
            controller.handle_message(f"uagv/v2/sim/{serial}/state", payload)
            handle.append(time.perf_counter() - started)

    for serial, vehicle in fleet.items():
        message = vda5050.encode(wire.connection(vehicle, ConnectionState.ONLINE))
        controller.handle_message(f"uagv/v2/sim/{serial}/connection", message)
        publish_state(serial)

    footprints = {s: footprint_of(v) for s, v in fleet.items()}
    checker = CollisionChecker()
    orders: dict[int, ActiveOrder] = {}
    targets: dict[int, tuple[str, str]] = {}
    finished, next_id, dt = 0, 1, 0.1
    for step in range(int(seconds / dt)):
        if step % 10 == 0:
            batch = controller.collect_flush()
            for p in batch.progress:
                if p.kind in {"finished", "failed", "requeued", "cancelled"}:
                    finished += p.kind == "finished"
                    orders.pop(p.order_id, None)
                    targets.pop(p.order_id, None)
            busy = {o.vehicle_pk for o in orders.values()}
            occupied = {v.last_node_id for v in fleet.values()}
            taken = {n for pair in targets.values() for n in pair}
            for pk, serial in enumerate(serials, start=1):
                vehicle = fleet[serial]
                if pk in busy or not vehicle.idle:
                    continue
                free = [s for s in spurs if s not in occupied and s not in taken]
                if len(free) < 2:
                    break
                pick, drop = rng.sample(free, 2)
                orders[next_id] = ActiveOrder(
                    next_id, f"TO-{next_id}", pk, [vehicle.last_node_id, pick, drop], pick,
                    "bench", "P", "D",
                )  # fmt: skip
                targets[next_id] = (pick, drop)
                taken |= {pick, drop}
                next_id += 1
            controller.sync(list(orders.values()))
        for serial, vehicle in fleet.items():
            vehicle.tick(dt)
            if vehicle.take_state_due() or step % 10 == 0:
                publish_state(serial)
        bodies = [Body(s, v.x, v.y, v.theta, footprints[s]) for s, v in fleet.items()]
        checker.check(bodies, step * dt)
    samples = traffic.stats.samples
    safety = traffic.safety(math.inf)
    return {
        "vehicles": vehicles,
        "simulated_seconds": seconds,
        "state_messages": len(handle),
        "orders_finished": finished,
        "collisions": checker.count,
        "delays_injected": sum(v.delays.injected for v in fleet.values() if v.delays),
        "wait_cycles": safety["cycles"],
        "release_decision_us_p50": round(statistics.median(samples) * 1e6, 1),
        "release_decision_us_p95": round(percentile(samples, 0.95) * 1e6, 1),
        "release_decision_us_p99": round(percentile(samples, 0.99) * 1e6, 1),
        "release_decision_us_max": round(max(samples) * 1e6, 1),
        "release_decisions_over_1ms": sum(1 for x in samples if x > 1e-3),
        "release_decisions": len(samples),
        "release_decision_cpu_us_p99": round(percentile(cpu, 0.99) * 1e6, 1),
        "release_decision_cpu_us_max": round(max(cpu) * 1e6, 1),
        "release_decisions_cpu_over_1ms": sum(1 for x in cpu if x > 1e-3),
        "handle_message_us_p50": round(statistics.median(handle) * 1e6, 1),
        "handle_message_us_p95": round(percentile(handle, 0.95) * 1e6, 1),
        "traffic_problems": dict(traffic.problems),
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--vehicles", type=int, default=14)
    parser.add_argument("--seconds", type=float, default=600.0, help="simulated seconds")
    parser.add_argument("--columns", type=int, default=16, help="aisle columns of the warehouse")
    parser.add_argument("--delay-share", type=float, default=0.05)
    args = parser.parse_args()
    figures = measure(args.vehicles, args.seconds, args.columns, args.delay_share)
    for key, value in figures.items():
        print(f"{key:28} {value}")
    results.write("traffic_control", figures)


if __name__ == "__main__":
    main()
