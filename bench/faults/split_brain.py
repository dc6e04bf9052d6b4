"""Split brain (RELIABILITY.md §3 row 10, §5): two `control` processes, one leading, while the
leader is SIGKILLed, frozen (SIGSTOP for `--freeze` s, then SIGCONT) or the row's own PostgreSQL
is restarted (`pg_ctl stop -m immediate`, start), round after round, with vehicles driving a
stream of orders.

    nice -n 5 .venv/bin/python -m bench.faults.split_brain --rounds 20 --freeze 20

Who published what comes from the broker itself: the row's Mosquitto logs every PUBLISH it
receives with the sender's client id (each control term has its own), and an independent
subscriber timestamps every order and instantActions message; the k-th message on a topic in
the log is the k-th the subscriber received (QoS 0, one broker, order kept), checked by size.
Figures: seconds with two publishers (overlap of the publishing spans of different terms) and
publishes by an older term after a newer one began (both must be 0), failover time (fault → the
other control answers 200 on `/ready`) p50/p95 per kind and overall (goal ≤ 15 s), orders lost,
duplicate-content publishes. Written to bench/results/split_brain.json (or `--out`).
"""

import argparse
import json
import os
import re
import shutil
import signal
import sys
import threading
import time
import uuid
from collections import defaultdict
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

import paho.mqtt.client as mqtt
from paho.mqtt.enums import CallbackAPIVersion

from bench import results
from bench.faults.fleet import Fleet, Observer, Process, percentile, python
from bench.faults.harness import Context, verdict, wait_all_closed, wait_online
from bench.faults.health_watch import HealthWatch
from bench.faults.stack import Stack, free_port

KINDS = ("kill", "freeze", "database")
MASTER_TOPICS = ("order", "instantActions")
PUBLISH_LINE = re.compile(
    r"Received PUBLISH from (\S+) \(d\d, q\d, r\d, m\d+, '([^']+)', \.\.\. \((\d+) bytes\)\)"
)


@contextmanager
def split_brain_context(seed: int, keep_logs: Path | None = None) -> Iterator[Context]:
    """The row's own services with a broker that logs each PUBLISH and its sender."""
    stack = Stack()
    conf = stack.mosquitto.conf
    conf.write_text(conf.read_text() + "log_type debug\nlog_type error\nlog_type warning\n")
    fleet: Fleet | None = None
    observer: Observer | None = None
    try:
        stack.start()
        os.environ.update(stack.env())
        os.environ["CELERY_TASK_ALWAYS_EAGER"] = "0"
        os.environ.setdefault("DJANGO_SETTINGS_MODULE", "fleet.settings")
        import django

        django.setup()
        from maps.demo import warehouse_layout
        from maps.services import create_layout

        fleet = Fleet(stack)
        os.environ["VDA5050_INTERFACE"] = fleet.interface
        observer = Observer(stack.mosquitto.url, fleet.interface)
        context = Context(stack=stack, fleet=fleet, observer=observer, full=True)
        context.rng.seed(seed)
        context.layout = create_layout(spec=warehouse_layout(columns=6, rows=4))
        fleet.write_layout(context.layout)
        yield context
    finally:
        if observer is not None:
            observer.stop()
        if fleet is not None:
            print(f"exit codes: {fleet.close()}", flush=True)
            if keep_logs is not None:
                shutil.copytree(fleet.log_dir, keep_logs, dirs_exist_ok=True)
                shutil.copy(stack.mosquitto.dir / "mosquitto.log", keep_logs)
        from django.db import connections

        connections.close_all()
        stack.close()


class MasterSniffer:
    """Timestamps every order and instantActions message, in arrival order per topic."""

    def __init__(self, url: str, interface: str) -> None:
        self.received: dict[str, list[tuple[float, int]]] = defaultdict(list)
        self.lock = threading.Lock()
        host, port = url.removeprefix("mqtt://").split(":")
        self.client = mqtt.Client(
            callback_api_version=CallbackAPIVersion.VERSION2,
            client_id=f"sniffer-{uuid.uuid4().hex[:8]}",
        )
        self.client.on_connect = lambda client, *_: client.subscribe(
            [(f"{interface}/+/+/+/{topic}", 0) for topic in MASTER_TOPICS]
        )
        self.client.on_message = self._on_message
        self.client.connect(host, int(port), keepalive=10)
        self.client.loop_start()

    def _on_message(self, client: mqtt.Client, userdata: Any, msg: mqtt.MQTTMessage) -> None:
        with self.lock:
            self.received[msg.topic].append((time.monotonic(), len(msg.payload)))

    def stop(self) -> None:
        self.client.loop_stop()
        self.client.disconnect()


def attribute_publishes(
    log_text: str, sniffer: MasterSniffer
) -> tuple[list[tuple[float, str]], int]:
    """(receive time, publisher client id) of every master message; and how many failed to match."""
    senders: dict[str, list[tuple[str, int]]] = defaultdict(list)
    for match in PUBLISH_LINE.finditer(log_text):
        client, topic, size = match.group(1), match.group(2), int(match.group(3))
        if topic.rsplit("/", 1)[-1] in MASTER_TOPICS:
            senders[topic].append((client, size))
    timeline: list[tuple[float, str]] = []
    mismatched = 0
    with sniffer.lock:
        received = {topic: list(items) for topic, items in sniffer.received.items()}
    for topic, arrivals in received.items():
        sent = senders.get(topic, [])
        mismatched += abs(len(sent) - len(arrivals))
        for (at, size), (client, logged_size) in zip(arrivals, sent, strict=False):
            mismatched += size != logged_size
            timeline.append((at, client))
    return sorted(timeline), mismatched


def publisher_overlap(timeline: list[tuple[float, str]]) -> dict[str, Any]:
    """Seconds in which two terms' publishing spans overlap, and stale publishes (by a term after
    a newer term's first publish)."""
    spans: dict[str, list[float]] = {}
    for at, client in timeline:
        span = spans.setdefault(client, [at, at])
        span[1] = at
    ordered = sorted(spans.items(), key=lambda item: item[1][0])
    overlap = 0.0
    for i, (_, (start_a, end_a)) in enumerate(ordered):
        for _, (start_b, end_b) in ordered[i + 1 :]:
            overlap += max(0.0, min(end_a, end_b) - max(start_a, start_b))
    first = {client: span[0] for client, span in spans.items()}
    stale = sum(
        1
        for at, client in timeline
        if any(first[c] > first[client] and at > first[c] for c in first)
    )
    return {
        "publisher_terms": len(spans),
        "two_publisher_seconds": round(overlap, 3),
        "stale_publishes": stale,
    }


class FreeStationFeeder(threading.Thread):
    """Keeps `in_flight` orders open, each from a pick to a drop station that no vehicle stands
    on and no open order uses: nothing sends idle vehicles away in this row, and one parked on
    a destination spur would block that order for good (a traffic matter, not this row's)."""

    def __init__(self, context: Context, in_flight: int) -> None:
        super().__init__(daemon=True)
        self.context, self.in_flight = context, in_flight
        self.ids: list[int] = []
        self.errors: list[str] = []
        self._halt = threading.Event()

    def run(self) -> None:
        from django.db import close_old_connections, connection

        try:
            while not self._halt.wait(0.5):
                try:
                    self._top_up()
                except Exception as exc:  # noqa: BLE001 - the database restarts in this row
                    self.errors.append(repr(exc))
                    close_old_connections()
        finally:
            connection.close()

    def _top_up(self) -> None:
        from maps.models import Station
        from orders.models import TransportOrder
        from orders.services import create_transport_order
        from robots.models import Vehicle

        open_orders = TransportOrder.objects.filter(status__in=TransportOrder.OPEN_STATUSES)
        if open_orders.count() >= self.in_flight:
            return
        taken = set(Vehicle.objects.values_list("last_node_id", flat=True))
        used = set(open_orders.values_list("source_id", flat=True))
        used |= set(open_orders.values_list("destination_id", flat=True))
        stations = Station.objects.filter(map=self.context.layout).select_related("node")
        free = [s for s in stations if s.node.node_id not in taken and s.pk not in used]
        picks = [s for s in free if s.kind == Station.Kind.PICK]
        drops = [s for s in free if s.kind == Station.Kind.DROP]
        if picks and drops:
            rng = self.context.rng
            order = create_transport_order(
                source=rng.choice(picks), destination=rng.choice(drops), load_id=f"L{len(self.ids)}"
            )
            self.ids.append(order.pk)

    def stop(self) -> None:
        self._halt.set()
        self.join(10)


def start_control(fleet: Fleet, name: str, port: int) -> Process:
    env = {**fleet.env, "CONTROL_HEALTH_PORT": str(port)}
    return fleet.add(name, python("manage.py", "run_control"), env)


def one_round(
    context: Context, kind: str, controls: dict[str, Process], watch: HealthWatch, freeze: float
) -> dict[str, Any]:
    """Inject one fault into the current leader; the seconds until a control is ready again."""
    fleet = context.fleet
    leader, fencing = watch.wait_settled(list(controls), 180, fleet)
    process = controls[leader]
    started = time.monotonic()
    if kind == "kill":
        process.kill()
    elif kind == "freeze":
        process.signal(signal.SIGSTOP)
    else:
        context.stack.postgres.stop_immediate()
        time.sleep(1.0)
        context.stack.postgres.start()

    def taken_over() -> bool:
        now = watch.ready_leader()
        if now is None or watch.latest[now[0]]["at"] <= started:
            return False
        return now[1] > fencing  # a new term (also after a database restart)

    failover = watch.wait(taken_over, 120, f"takeover after {kind}", None)
    new_leader = (watch.ready_leader() or ("?", 0))[0]
    if kind == "kill":
        process.start()
    elif kind == "freeze":
        time.sleep(max(0.0, freeze - (time.monotonic() - started)))
        process.signal(signal.SIGCONT)
    watch.wait(
        lambda: watch.role(leader) == "standby" or leader == new_leader,
        180,  # a restarted control imports Django first: slow on a loaded machine
        "old leader back as standby",
        fleet,
    )
    print(
        f"round {kind}: {leader} (fencing {fencing}) → {new_leader} in {failover:.1f} s", flush=True
    )
    return {"kind": kind, "from": leader, "to": new_leader, "failover_s": round(failover, 2)}


def run(
    *, rounds: int, freeze: float, vehicles: int, seed: int = 5050, keep_logs: Path | None = None
) -> dict[str, Any]:
    with split_brain_context(seed, keep_logs) as context:
        from django.db import connections

        fleet = context.fleet
        ports = {"control-a": free_port(), "control-b": free_port()}
        controls = {name: start_control(fleet, name, port) for name, port in ports.items()}
        sniffer = MasterSniffer(context.stack.mosquitto.url, fleet.interface)
        watch = HealthWatch(ports)
        watch.start()
        fleet.worker(beat=True)
        fleet.simulator("simulator", count=vehicles, extra=("--visualization-hz", "0"))
        wait_online(context, vehicles, timeout=120)
        feeder = FreeStationFeeder(context, in_flight=max(1, vehicles - 1))
        feeder.start()
        kinds = [KINDS[i % len(KINDS)] for i in range(rounds)]
        context.rng.shuffle(kinds)
        outcomes = []
        try:
            for kind in kinds:
                time.sleep(context.rng.uniform(2, 5))
                outcomes.append(one_round(context, kind, controls, watch, freeze))
                connections.close_all()  # ours died with a database restart
        finally:
            feeder.stop()
        drained = wait_all_closed(context, feeder.ids, timeout=300)
        figures = verdict(context, feeder.ids)
        time.sleep(1.0)
        sniffer.stop()
        watch.stop()
        log_text = (context.stack.mosquitto.dir / "mosquitto.log").read_text(errors="replace")
        timeline, mismatched = attribute_publishes(log_text, sniffer)
        failovers = [o["failover_s"] for o in outcomes]
        figures.update(publisher_overlap(timeline))
        figures.update(
            {
                "rounds": len(outcomes),
                "rounds_by_kind": {k: kinds.count(k) for k in KINDS},
                "freeze_s": freeze,
                "vehicles": vehicles,
                "master_publishes_attributed": len(timeline),
                "attribution_mismatches": mismatched,
                "failover_s_p50": percentile(failovers, 0.5),
                "failover_s_p95": percentile(failovers, 0.95),
                "failover_s_max": percentile(failovers, 1.0),
                "drain_s": None if drained is None else round(drained, 1),
                "round_log": outcomes,
            }
        )
        for kind in KINDS:
            values = [o["failover_s"] for o in outcomes if o["kind"] == kind]
            figures[f"failover_{kind}_s_p50"] = percentile(values, 0.5)
            figures[f"failover_{kind}_s_p95"] = percentile(values, 0.95)
        figures["passed"] = bool(
            figures["nothing_lost"]
            and figures["two_publisher_seconds"] == 0
            and figures["stale_publishes"] == 0
            and (figures["failover_s_p95"] or 0) <= 15.0
        )
        return figures


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    parser.add_argument("--rounds", type=int, default=20)
    parser.add_argument(
        "--freeze", type=float, default=20.0, help="seconds a frozen leader stays stopped"
    )
    parser.add_argument("--vehicles", type=int, default=3)
    parser.add_argument("--out", type=Path, help="write the figures here, not bench/results")
    parser.add_argument("--keep-logs", type=Path, help="copy the processes' and broker's logs here")
    args = parser.parse_args(argv)
    started = time.monotonic()
    figures = run(
        rounds=args.rounds, freeze=args.freeze, vehicles=args.vehicles, keep_logs=args.keep_logs
    )
    figures["seconds"] = round(time.monotonic() - started, 1)
    if args.out:
        args.out.write_text(json.dumps(figures, indent=2, sort_keys=True) + "\n")
    else:
        # A quick run (CI, `make bench-faults`) must not overwrite the §5 figure of 20 rounds.
        results.write("split_brain" if args.rounds >= 20 else "split_brain_quick", figures)
    summary = {k: v for k, v in figures.items() if k != "round_log"}
    print(f"FIGURE split_brain: {json.dumps(summary, sort_keys=True)}", flush=True)
    return 0 if figures["passed"] else 1


if __name__ == "__main__":
    sys.exit(main())
