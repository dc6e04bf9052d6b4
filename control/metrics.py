"""What `control` counts, and the snapshot the web `/metrics` page renders (fleet.metrics).

The hot path only adds to in-memory counters and fixed-bucket histograms (a dict increment
and a bisect per message); a background thread writes a JSON snapshot to Redis every few
seconds, so a scrape never touches the paho thread. Counted here: messages by topic kind,
time spent handling a message, the latency from a state message's arrival to the order
(update) it made `control` publish, garbage-collection pauses, and how late a thread that asked
to run gets to (`wakeup_delay`: what a message waiting in the socket waits while another thread
holds the GIL). The controller's own protocol counters (decode errors, rejections, sent
messages, …) go out with the snapshot as they are.
"""

import bisect
import gc
import json
import logging
import os
import threading
import time
from collections import Counter
from collections.abc import Callable
from typing import TYPE_CHECKING, Any

import msgspec
import paho.mqtt.client as mqtt

if TYPE_CHECKING:
    from control.controller import Controller
    from control.runner import MqttLink

logger = logging.getLogger(__name__)

SNAPSHOT_KEY = "fleet:control:metrics"
SNAPSHOT_INTERVAL = 2.0  # seconds between snapshots in Redis
# Seconds; Prometheus `le` bounds. Fine at the low end: the target is p99 <= 50 ms.
LATENCY_BUCKETS = (0.0001, 0.00025, 0.0005, 0.001, 0.0025, 0.005, 0.01, 0.025, 0.05, 0.1, 0.25, 1.0)
# Pauses and stalls: up to seconds (a full collection of a large heap, a long plan).
STALL_BUCKETS = (0.001, 0.0025, 0.005, 0.01, 0.025, 0.05, 0.1, 0.25, 0.5, 1.0, 2.5)
# A state's age when applied: milliseconds on one host, up to seconds with a backlog.
AGE_BUCKETS = (0.005, 0.01, 0.025, 0.05, 0.1, 0.25, 0.5, 1.0, 2.5, 5.0, 10.0, 30.0)
WAKEUP_PERIOD = 0.02  # s the wake-up probe sleeps between two measurements


class Histogram:
    """Cumulative-at-render histogram with fixed bounds; `observe` is a bisect and two adds."""

    def __init__(self, bounds: tuple[float, ...] = LATENCY_BUCKETS) -> None:
        self.bounds = bounds
        self.counts = [0] * (len(bounds) + 1)  # the last one is +Inf
        self.total = 0.0

    def observe(self, seconds: float) -> None:
        self.counts[bisect.bisect_left(self.bounds, seconds)] += 1
        self.total += seconds

    def as_dict(self) -> dict[str, Any]:
        return {"bounds": list(self.bounds), "counts": list(self.counts), "sum": self.total}


class _Ids(msgspec.Struct):
    """The ids of a state or an order message that pair them across processes."""

    headerId: int = -1  # noqa: N815 (VDA 5050 field names)
    orderId: str = ""  # noqa: N815
    orderUpdateId: int = 0  # noqa: N815


class CauseLog:
    """Which state message made `control` publish each order update (CONTROL_CAUSE_LOG).

    For the load benchmark only (off by default): its probe at the broker times each update
    from the arrival of the state that caused it, also when that state is another vehicle's
    (a vehicle waiting for traffic is released by the one it waited for). One JSON line per
    update: the order topic, orderId, orderUpdateId, and the state's topic and headerId.
    Written from the paho thread, line-buffered: a few dozen lines a second."""

    def __init__(self, path: str) -> None:
        self._file = open(path, "a", buffering=1, encoding="utf-8")  # noqa: SIM115 (process-long)
        self._decode = msgspec.json.Decoder(_Ids).decode

    def record(
        self, order_topic: str, order: bytes, state_topic: str, state: bytes | bytearray
    ) -> None:
        try:
            update, cause = self._decode(order), self._decode(state)
        except msgspec.DecodeError:
            return
        line = {
            "order": order_topic,
            "orderId": update.orderId,
            "orderUpdateId": update.orderUpdateId,
            "state": state_topic,
            "headerId": cause.headerId,
        }
        self._file.write(json.dumps(line) + "\n")


class ControlMetrics:
    """Messages by topic, handling time and state → order latency of one `control` process."""

    def __init__(self, controller: "Controller") -> None:
        self.controller = controller
        self.by_topic: Counter[str] = Counter()
        self.handling = Histogram()
        self.state_to_order = Histogram()
        # From a state's timestamp to control having applied it: the ingest lag where the
        # vehicles' clocks agree with control's (plus their skew where they do not)
        self.state_age = Histogram(AGE_BUCKETS)
        self.gc_pause = {"young": Histogram(STALL_BUCKETS), "full": Histogram(STALL_BUCKETS)}
        self.wakeup_delay = Histogram(STALL_BUCKETS)
        self._gc_started = 0.0
        self.started = time.time()
        self._current: tuple[int, float] | None = None  # (paho thread, arrival) while handling
        self._cause: tuple[str, bytes | bytearray] = ("", b"")  # the state handled (CauseLog)
        self.link_connected: threading.Event | None = None

    def instrument(self, link: "MqttLink", causes: CauseLog | None = None) -> None:
        """Wrap the link's message callback and the controller's publish function (and with
        `causes`, log which state made each order update)."""
        handle: Callable[[mqtt.Client, Any, mqtt.MQTTMessage], None] | None
        handle = link.client.on_message
        assert handle is not None, "instrument the link after MqttLink set its callback"
        publish = self.controller.publisher.publish
        self.link_connected = link.connected

        # Bound once: this wrapper runs for every message (thousands a second).
        clock, thread_id = time.perf_counter, threading.get_ident
        by_topic, handling, state_age = self.by_topic, self.handling, self.state_age
        skew_of = self.controller.clock_skew_of

        def on_message(client: mqtt.Client, userdata: Any, message: mqtt.MQTTMessage) -> None:
            arrived = clock()
            topic = message.topic
            kind = topic[topic.rfind("/") + 1 :]
            by_topic[kind] += 1
            self._current = (thread_id(), arrived) if kind == "state" else None
            if causes is not None:
                self._cause = (topic, message.payload)
            try:
                handle(client, userdata, message)
            finally:
                self._current = None
                handling.observe(clock() - arrived)
            if kind == "state":
                age = skew_of(topic)
                if age is not None:
                    state_age.observe(max(age, 0.0))

        def timed_publish(topic: str, payload: bytes, qos: int) -> None:
            publish(topic, payload, qos)
            current = self._current
            if (
                current is not None
                and topic.endswith("/order")
                and current[0] == threading.get_ident()
            ):
                self.state_to_order.observe(time.perf_counter() - current[1])
                if causes is not None:
                    causes.record(topic, payload, *self._cause)

        link.client.on_message = on_message
        self.controller.publisher.publish = timed_publish

    def watch_pauses(self, until: threading.Event) -> threading.Thread:
        """Time every garbage collection (young: generations 0-1; full: 2) and, on a daemon
        thread until `until` is set, how late a sleeping thread wakes up: both stall the paho
        thread, whose messages wait in the socket meanwhile. The collector hook goes with the
        thread."""
        if self._on_gc not in gc.callbacks:
            gc.callbacks.append(self._on_gc)
        thread = threading.Thread(
            target=self._probe_wakeups, args=(until,), name="control-wakeup-probe", daemon=True
        )
        thread.start()
        return thread

    def _on_gc(self, phase: str, info: dict[str, int]) -> None:
        if phase == "start":
            self._gc_started = time.perf_counter()
        else:
            pause = time.perf_counter() - self._gc_started
            self.gc_pause["full" if info["generation"] == 2 else "young"].observe(pause)

    def _probe_wakeups(self, until: threading.Event) -> None:
        clock = time.perf_counter
        while not until.is_set():
            asked = clock()
            time.sleep(WAKEUP_PERIOD)
            self.wakeup_delay.observe(max(0.0, clock() - asked - WAKEUP_PERIOD))
        gc.callbacks[:] = [c for c in gc.callbacks if c != self._on_gc]

    def snapshot(self) -> dict[str, Any]:
        """Plain data for Redis: counters, histograms and the live fleet by state."""
        controller = self.controller
        with controller.lock:
            vehicles = list(controller.fleet.vehicles.values())
            links: Counter[str] = Counter(str(v.last_link.value) for v in vehicles)
            executing = sum(1 for v in vehicles if v.execution is not None)
            per_vehicle: Counter[str] = Counter()  # header gaps = messages lost on the way
            for vehicle in vehicles:
                per_vehicle.update(vehicle.session.counters)
            counters = dict(controller.counters)
            if controller.traffic is not None:  # unlocked route searches done again, held
                managers = controller.traffic.managers.values()
                counters["traffic_searches_repeated"] = sum(m.searches_repeated for m in managers)
                counters["traffic_searches_moved"] = sum(m.searches_moved for m in managers)
                # the tick's re-plans of waiting vehicles, and those that kept the route
                counters["traffic_replans"] = sum(m.replans for m in managers)
                counters["traffic_replans_unchanged"] = sum(m.replans_unchanged for m in managers)
                # progress beyond the base, vehicles that cannot be placed, ... (logged too);
                # an order start that found no plan now (it is tried again) is counted apart
                problems, no_plan = controller.traffic.problem_counts()
                counters["traffic_problems"], counters["traffic_no_plan"] = problems, no_plan
                safety = controller.traffic.safety(time.monotonic())
            else:
                safety = {}
        return {
            "time": time.time(),
            "started": self.started,
            "pid": os.getpid(),
            "broker_connected": bool(self.link_connected and self.link_connected.is_set()),
            "counters": counters,
            "vehicle_counters": dict(per_vehicle),
            "messages_by_topic": dict(self.by_topic),
            "handling_seconds": self.handling.as_dict(),
            "state_to_order_seconds": self.state_to_order.as_dict(),
            "state_age_seconds": self.state_age.as_dict(),
            "gc_young_pause_seconds": self.gc_pause["young"].as_dict(),
            "gc_full_pause_seconds": self.gc_pause["full"].as_dict(),
            "wakeup_delay_seconds": self.wakeup_delay.as_dict(),
            "vehicles": len(vehicles),
            "vehicles_by_link": dict(links),
            "vehicles_executing": executing,
            # the traffic safety net: wait-for cycles and stalled vehicles (both must stay 0)
            "traffic_safety": safety,
            "cpu_seconds": time.process_time(),
        }


def start_snapshots(
    metrics: ControlMetrics,
    redis_url: str,
    *,
    interval: float = SNAPSHOT_INTERVAL,
    until: threading.Event | None = None,
) -> threading.Thread | None:
    """Write `metrics.snapshot()` to Redis every `interval` s until `until` is set (a daemon
    thread); None: no Redis."""
    until = until or threading.Event()
    if not redis_url:
        return None
    import redis

    client = redis.Redis.from_url(redis_url, socket_timeout=5)

    def run() -> None:
        while not until.is_set():
            try:
                data = json.dumps(metrics.snapshot())
                client.set(SNAPSHOT_KEY, data, ex=max(10, int(interval * 5)))
            except Exception:  # metrics must never take control down
                logger.warning("metrics snapshot failed", exc_info=True)
            until.wait(interval)

    thread = threading.Thread(target=run, name="control-metrics", daemon=True)
    thread.start()
    return thread
