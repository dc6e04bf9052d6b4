"""The measuring processes of the load benchmark, each writing one JSON file at the end.

    python -m bench.load.probes raw --broker HOST:PORT --interface I --start T --seconds S --out F
    python -m bench.load.probes api ... --url URL --token TOKEN --layout F --rate R --vehicles N
    python -m bench.load.probes ws ... --url URL --session KEY

All three wait until wall time `--start` (epoch seconds), measure for `--seconds`, then write.
`raw` is the floor for `control`: a bare paho client on the same topics (same QoS) that only
counts, and, on the order topic, the time from a vehicle's state that reported progress to
the order update answering it (the state → order-update latency, broker hops included).
`api` posts transport orders at a steady rate and times POST → the order's first message on
the order topic.
`ws` is a browser on the live page: websocket messages and vehicle rows per second.
"""

import argparse
import asyncio
import gc
import json
import os
import random
import time
import urllib.request
import uuid
from collections.abc import Callable
from pathlib import Path
from typing import Any

import msgspec
import paho.mqtt.client as mqtt
from paho.mqtt.enums import CallbackAPIVersion

CONTROL_TOPICS = (("state", 0), ("connection", 1), ("factsheet", 0), ("visualization", 0))
ZONE = 3  # aisle nodes (18 m) around a vehicle's home where a zone order picks and drops


def percentile(samples: list[float], q: float) -> float | None:
    if not samples:
        return None
    ordered = sorted(samples)
    return ordered[min(len(ordered) - 1, round(q * (len(ordered) - 1)))]


def ms(value: float | None) -> float | None:
    return None if value is None else round(value * 1e3, 2)


def _client(name: str, host: str, port: int) -> mqtt.Client:
    client = mqtt.Client(CallbackAPIVersion.VERSION2, client_id=f"loadbench-{name}-{os.getpid()}")
    client.connect(host, port, 30)
    return client


def _wait_until(start: float) -> None:
    time.sleep(max(0.0, start - time.time()))


class _Progress(msgspec.Struct):
    """The two fields of a state that ask the master control for more base."""

    lastNodeSequenceId: int = 0  # noqa: N815 (VDA 5050 field names)
    newBaseRequest: bool = False  # noqa: N815
    headerId: int = -1  # noqa: N815


_decode_progress = msgspec.json.Decoder(_Progress).decode


def raw(args: argparse.Namespace) -> dict[str, Any]:
    """Count what paho alone receives on control's topics; time state → order update.

    The latency is causal: an order update answers a vehicle's state when that state reported
    progress (a higher lastNodeSequenceId, or newBaseRequest newly set) and arrives before the
    vehicle's next state; it is timed from that state's arrival here, so both broker hops and
    any backlog in control count. Other updates (released by another vehicle's progress, or
    by control's periodic sync) are counted apart."""
    host, port = args.broker.split(":")
    client = _client("raw", host, int(port))
    iface = args.interface
    window = {"on": False}
    counts: dict[str, int] = dict.fromkeys((k for k, _ in CONTROL_TOPICS), 0)
    # Per vehicle: arrival of its latest state if that state asked for progress and is still
    # unanswered, else None; and its last node sequence id.
    asking: dict[str, float | None] = {}
    last_node: dict[str, int] = {}
    base_request: dict[str, bool] = {}
    latencies: list[float] = []
    other_updates = [0]
    unanswered = [0]
    new_orders = [0]
    # For the causal latency (`_causal`): arrival of every state by (vehicle, headerId), and
    # of every order message in the window by (vehicle, orderId, orderUpdateId).
    # Per vehicle, its states' arrivals by headerId: a few hundred entries each, so the probe
    # does not stall resizing one dict of hundreds of thousands of entries.
    state_seen: dict[str, dict[int, float]] = {}
    order_seen: dict[tuple[str, str, int], float] = {}

    def on_message(_c: mqtt.Client, _u: Any, message: mqtt.MQTTMessage) -> None:
        now = time.perf_counter()
        topic = message.topic
        kind = topic[topic.rfind("/") + 1 :]
        if kind == "state":
            vehicle = topic[:-6]
            try:
                progress = _decode_progress(message.payload)
            except msgspec.DecodeError:
                return
            state_seen.setdefault(vehicle, {})[progress.headerId] = now
            moved = progress.lastNodeSequenceId > last_node.get(vehicle, 0)
            last_node[vehicle] = progress.lastNodeSequenceId
            # newBaseRequest stays set while a vehicle waits for traffic: only its rising edge
            # asks; the update that ends such a wait answers another vehicle's progress.
            asked_base = progress.newBaseRequest and not base_request.get(vehicle, False)
            base_request[vehicle] = progress.newBaseRequest
            if window["on"] and asking.get(vehicle) is not None:
                unanswered[0] += 1  # its previous request got no update before this state
            asking[vehicle] = now if (moved or asked_base) else None
        elif kind == "order":
            if window["on"]:
                vehicle = topic[:-6]
                order = msgspec.json.decode(message.payload)
                update = order.get("orderUpdateId", 0)
                order_seen[(vehicle, order.get("orderId", ""), update)] = now
                asked = asking.get(vehicle)
                if update == 0:
                    new_orders[0] += 1
                elif asked is not None:
                    latencies.append(now - asked)
                    asking[vehicle] = None
                else:
                    other_updates[0] += 1
            return
        if window["on"]:
            counts[kind] += 1

    client.on_message = on_message
    client.subscribe([(f"{iface}/+/+/+/{k}", q) for k, q in CONTROL_TOPICS])
    client.subscribe(f"{iface}/+/+/+/order", 0)
    client.loop_start()
    _wait_until(args.start)
    gc.disable()  # a collection would delay the arrival times this probe records
    window["on"], cpu0, t0 = True, time.process_time(), time.perf_counter()
    time.sleep(args.seconds)
    window["on"], cpu1, t1 = False, time.process_time(), time.perf_counter()
    # Leave the broker before collecting: the first collection after half an hour without one
    # stalled this probe's network thread for a second and Mosquitto dropped 116 messages
    # for it at the very end of the window (eleventh round).
    client.disconnect()
    client.loop_stop()
    gc.enable()
    wall = t1 - t0
    total = sum(counts.values())
    return {
        "seconds": round(wall, 2),
        "messages": total,
        "messages_per_s": round(total / wall, 1),
        "by_topic_per_s": {k: round(v / wall, 1) for k, v in counts.items()},
        "cpu_share": round((cpu1 - cpu0) / wall, 4),
        "order_updates": len(latencies),
        "order_updates_other": other_updates[0],
        "progress_states_unanswered": unanswered[0],
        "new_orders": new_orders[0],
        "state_to_update_p50_ms": ms(percentile(latencies, 0.5)),
        "state_to_update_p99_ms": ms(percentile(latencies, 0.99)),
        **_causal(args.causes, state_seen, order_seen),
    }


def _causal(
    path: str | None,
    state_seen: dict[str, dict[int, float]],
    order_seen: dict[tuple[str, str, int], float],
) -> dict[str, Any]:
    """State → update latency by cause: control logs which state made it publish each order
    update (CONTROL_CAUSE_LOG); each update that arrived here in the window is timed from that
    state's arrival here. Unlike the heuristic above, an update that releases a vehicle waiting
    for traffic counts from the other vehicle's state that freed the way, not from the waiting
    vehicle's own last state. Updates control published without a state (its periodic sync,
    a new order) have no cause and are not counted."""
    if not path or not Path(path).exists():
        return {}
    latencies: list[float] = []
    unmatched = 0
    for line in Path(path).read_text().splitlines():
        cause = json.loads(line)
        order = (cause["order"][:-6], cause["orderId"], cause["orderUpdateId"])
        arrived = order_seen.get(order)
        if arrived is None:
            continue  # outside the window
        asked = state_seen.get(cause["state"][:-6], {}).get(cause["headerId"])
        if asked is None:
            unmatched += 1
            continue
        latencies.append(arrived - asked)
    return {
        "caused_updates": len(latencies),
        "caused_updates_unmatched": unmatched,
        "state_to_update_causal_p50_ms": ms(percentile(latencies, 0.5)),
        "state_to_update_causal_p99_ms": ms(percentile(latencies, 0.99)),
        "state_to_update_causal_max_ms": ms(max(latencies, default=None)),
    }


WORKLOADS = {
    "zone": "each order names its vehicle round-robin: pick and drop at two shelves within "
    f"{ZONE} aisle nodes of its home, then an action at home",
    "cross": "each order names its vehicle round-robin: pick on the top row, drop on the bottom "
    "row, then an action at home (every order crosses the grid)",
    "any": "pick on the top row, drop on the bottom row, for whichever vehicle dispatch finds "
    "(it then stands on the drop station until parked)",
}


def _workload(
    workload: str, layout: dict[str, Any], rng: random.Random
) -> Callable[[str], list[dict[str, Any]]]:
    """The pick and drop steps of the next order, given the home station of its vehicle."""
    by_kind: dict[str, list[str]] = {}
    for station in layout["stations"]:
        by_kind.setdefault(station["kind"], []).append(station["id"])
    if workload != "zone":
        picks, drops = by_kind["PICK"], by_kind["DROP"]
        return lambda _home: [
            {"station": rng.choice(picks), "operation": "PICK"},
            {"station": rng.choice(drops), "operation": "DROP"},
        ]
    shelves = set(by_kind["HANDOVER"])

    def near(home: str) -> list[dict[str, Any]]:
        # PARK-ccc-rrr: the shelves SHELF-ccc-rrr within ZONE columns and rows of it
        _, column, row = home.split("-")
        around = [
            f"SHELF-{c:03d}-{r:03d}"
            for c in range(int(column) - ZONE, int(column) + ZONE + 1)
            for r in range(int(row) - ZONE, int(row) + ZONE + 1)
        ]
        pick, drop = rng.sample([s for s in around if s in shelves], 2)
        return [
            {"station": pick, "operation": "PICK"},
            {"station": drop, "operation": "DROP"},
        ]

    return near


def api(args: argparse.Namespace) -> dict[str, Any]:
    """POST transport orders at `rate`/s; time POST → the order's first message on MQTT.

    The `workload` says what the orders are (`WORKLOADS`)."""
    layout = json.loads(Path(args.layout).read_text())
    fleet = json.loads(Path(args.fleet).read_text())  # [serial number, home park station]
    next_steps = _workload(args.workload, layout, random.Random(7))
    host, port = args.broker.split(":")
    client = _client("api", host, int(port))
    # Wall-clock times (s), comparable with the database's created/assigned times.
    published: dict[str, float] = {}

    def on_message(_c: mqtt.Client, _u: Any, message: mqtt.MQTTMessage) -> None:
        now = time.time()
        data = msgspec.json.decode(message.payload)
        if data.get("orderUpdateId") == 0:
            published.setdefault(str(data.get("orderId")), now)

    client.on_message = on_message
    client.subscribe(f"{args.interface}/+/+/+/order", 0)
    client.loop_start()
    posted: dict[str, float] = {}
    post_seconds: list[float] = []
    errors: list[str] = []
    _wait_until(args.start)
    t0 = time.perf_counter()
    end = t0 + args.seconds
    n = 0
    while (due := t0 + n / args.rate) < end:
        time.sleep(max(0.0, due - time.perf_counter()))
        serial, home = fleet[n % len(fleet)]
        steps = next_steps(home)
        body: dict[str, Any] = {"steps": steps, "external_ref": f"LOAD-{n}"}
        if args.workload != "any":
            # each order names its vehicle in turn and sends it back home at the end
            steps.append({"station": home, "operation": "ACTION", "action_type": "stopCharging"})
            body["intended_vehicle"] = serial
        request = urllib.request.Request(
            f"{args.url}/api/v1/orders/",
            data=json.dumps(body).encode(),
            method="POST",
            headers={
                "Authorization": f"Bearer {args.token}",
                "Content-Type": "application/json",
                "Idempotency-Key": str(uuid.uuid4()),
            },
        )
        started = time.time()
        try:
            with urllib.request.urlopen(request, timeout=30) as response:
                order_id = f"TO-{json.loads(response.read())['id']}"
            posted[order_id] = started
            post_seconds.append(time.time() - started)
        except Exception as exc:  # counted and reported, the run goes on
            errors.append(str(exc)[:200])
        n += 1
    time.sleep(args.grace)
    client.disconnect()
    client.loop_stop()
    delays = [published[o] - t for o, t in posted.items() if o in published]
    return {
        "posted": len(posted),
        "errors": len(errors),
        "first_errors": errors[:3],
        "published": len(delays),
        "post_p50_ms": ms(percentile(post_seconds, 0.5)),
        "post_p95_ms": ms(percentile(post_seconds, 0.95)),
        "post_to_published_p50_ms": ms(percentile(delays, 0.5)),
        "post_to_published_p95_ms": ms(percentile(delays, 0.95)),
        "post_to_published_max_ms": ms(max(delays) if delays else None),
        # order id -> [POST started, first order message seen] (wall clock; the run joins
        # them with the database's created/assigned times and drops this list)
        "timeline": {o: [t, published.get(o)] for o, t in posted.items()},
    }


def ws(args: argparse.Namespace) -> dict[str, Any]:
    """Count live-page websocket messages and vehicle rows per second; a connection the server
    closes is counted (with its reason) and opened again, as the page does."""
    import websockets

    url = args.url.replace("http://", "ws://") + "/ws/live/"
    headers = {"Cookie": f"sessionid={args.session}", "Origin": args.url}
    counts = {"messages": 0, "vehicle_rows": 0, "bytes": 0, "closed": 0}
    reasons: list[str] = []

    async def receive(socket: Any, end: float) -> None:
        while (left := end - time.perf_counter()) > 0:
            try:
                text = await asyncio.wait_for(socket.recv(), timeout=left)
            except TimeoutError:
                return
            counts["messages"] += 1
            counts["bytes"] += len(text)
            data = json.loads(text)
            counts["vehicle_rows"] += len(data.get("payload", {}).get("vehicles", []))

    async def run() -> float:
        window: list[float] = []  # [start, end], set once the first connection is open

        def begin() -> float:
            if not window:
                _wait_until(args.start)  # connected (and watching) before the window opens
                window.extend([time.perf_counter(), time.perf_counter() + args.seconds])
            return window[1]

        while not window or window[1] - time.perf_counter() > 0:
            try:
                async with websockets.connect(
                    url, additional_headers=headers, max_size=None
                ) as socket:
                    await receive(socket, begin())
            except (websockets.ConnectionClosed, OSError) as exc:
                counts["closed"] += 1
                reasons.append(str(exc)[:120])
                begin()
                await asyncio.sleep(1.0)
        return time.perf_counter() - window[0]

    wall = asyncio.run(run())
    return {
        "messages_per_s": round(counts["messages"] / wall, 1),
        "vehicle_rows_per_s": round(counts["vehicle_rows"] / wall, 1),
        "kbytes_per_s": round(counts["bytes"] / wall / 1024, 1),
        "closed_by_server": counts["closed"],
        "close_reasons": sorted(set(reasons))[:3],
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("probe", choices=("raw", "api", "ws"))
    parser.add_argument("--broker", default="127.0.0.1:1883")
    parser.add_argument("--interface", default="uagv")
    parser.add_argument("--start", type=float, required=True, help="epoch seconds")
    parser.add_argument("--seconds", type=float, required=True)
    parser.add_argument("--out", type=Path, required=True)
    parser.add_argument("--url", default="")
    parser.add_argument("--token", default="")
    parser.add_argument("--session", default="")
    parser.add_argument("--layout", default="")
    parser.add_argument("--rate", type=float, default=1.0)
    parser.add_argument("--fleet", default="", help="JSON [[serial, home station], ...]")
    parser.add_argument("--workload", choices=tuple(WORKLOADS), default="zone")
    parser.add_argument("--causes", default="", help="control's CONTROL_CAUSE_LOG (raw)")
    parser.add_argument("--grace", type=float, default=5.0, help="wait for the last orders")
    args = parser.parse_args()
    result = {"raw": raw, "api": api, "ws": ws}[args.probe](args)
    args.out.write_text(json.dumps(result, indent=2))


if __name__ == "__main__":
    main()
