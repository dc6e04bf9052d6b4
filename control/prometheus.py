"""`GET /metrics`: the fleet in Prometheus text format, for monitoring.

What `control` counts in memory arrives as the snapshot it writes to Redis every 2 s
(`control.metrics`); the rest is read when scraped: vehicles by connection and operating mode
and transport orders by status (the database), the Celery queue and `control`'s command queue
(Redis list lengths). Counters are totals since `control` started: rates (messages per second by
topic) come from PromQL, e.g. `rate(fleet_control_messages_received_total[1m])`.

Access: anonymous scrapes only from METRICS_ALLOWED_CIDRS (default 127.0.0.1/32), anyone else
with `Authorization: Bearer <METRICS_TOKEN>` (docs/LOAD.md).
"""

import hmac
import ipaddress
import json
import logging
import time
from collections.abc import Iterator
from functools import cache
from typing import Any

import redis
from django.conf import settings
from django.db.models import Count
from django.http import HttpRequest, HttpResponse
from django.views.decorators.http import require_GET
from prometheus_client import CONTENT_TYPE_LATEST, CollectorRegistry, generate_latest
from prometheus_client.core import (
    CounterMetricFamily,
    GaugeMetricFamily,
    HistogramMetricFamily,
    Metric,
)

from control.metrics import SNAPSHOT_KEY
from fleet.control_queue import QUEUE_KEY
from orders.models import TransportOrder
from robots.models import Vehicle

logger = logging.getLogger(__name__)

STALE_AFTER = 15.0  # s: an older snapshot means `control` is down or cannot reach Redis
CELERY_QUEUE = "celery"  # the default queue's Redis list


@cache
def _networks(cidrs: tuple[str, ...]) -> tuple[ipaddress.IPv4Network | ipaddress.IPv6Network, ...]:
    return tuple(ipaddress.ip_network(c.strip(), strict=False) for c in cidrs if c.strip())


def scrape_allowed(request: HttpRequest) -> bool:
    """A valid bearer token, or a client address inside METRICS_ALLOWED_CIDRS."""
    token = settings.METRICS_TOKEN
    header = request.headers.get("Authorization", "")
    if token and header.startswith("Bearer "):
        return hmac.compare_digest(header.removeprefix("Bearer ").encode(), token.encode())
    try:
        address = ipaddress.ip_address(request.META.get("REMOTE_ADDR", ""))
    except ValueError:
        return False
    return any(address in network for network in _networks(tuple(settings.METRICS_ALLOWED_CIDRS)))


class FleetCollector:
    """Turns the control snapshot and the scraped figures into Prometheus metric families."""

    def __init__(
        self,
        snapshot: dict[str, Any] | None,
        vehicles: list[dict[str, Any]],
        orders: dict[str, int],
        queues: dict[str, int | None],
        now: float,
    ) -> None:
        self.snapshot, self.vehicles, self.orders, self.queues = snapshot, vehicles, orders, queues
        self.now = now

    def collect(self) -> Iterator[Metric]:
        yield from self._control()
        vehicles = GaugeMetricFamily(
            "fleet_vehicles",
            "Registered vehicles by connection and operating mode (database).",
            labels=["connection", "operating_mode"],
        )
        for row in self.vehicles:
            vehicles.add_metric([row["connection"], row["operating_mode"] or "UNKNOWN"], row["n"])
        yield vehicles
        orders = GaugeMetricFamily(
            "fleet_transport_orders", "Transport orders by status (database).", labels=["status"]
        )
        for status in TransportOrder.Status.values:
            orders.add_metric([status], self.orders.get(status, 0))
        yield orders
        queues = GaugeMetricFamily(
            "fleet_queue_length", "Messages waiting in a Redis queue.", labels=["queue"]
        )
        for name, length in self.queues.items():
            if length is not None:
                queues.add_metric([name], length)
        yield queues

    def _control(self) -> Iterator[Metric]:
        snapshot = self.snapshot
        fresh = snapshot is not None and self.now - snapshot.get("time", 0) < STALE_AFTER
        yield GaugeMetricFamily(
            "fleet_control_up", "1 when control published metrics in the last 15 s.", int(fresh)
        )
        if snapshot is None or not fresh:
            return
        yield GaugeMetricFamily(
            "fleet_control_broker_connected",
            "1 when control's MQTT client is connected.",
            int(bool(snapshot.get("broker_connected"))),
        )
        yield _labelled(
            CounterMetricFamily,
            "fleet_control_messages_received",
            "MQTT messages control received, by topic kind.",
            "topic",
            snapshot.get("messages_by_topic", {}),
        )
        counters = snapshot.get("counters", {})
        yield CounterMetricFamily(
            "fleet_control_decode_errors",
            "Messages dropped because they did not decode.",
            counters.get("decode_errors", 0),
        )
        yield _labelled(
            CounterMetricFamily,
            "fleet_control_events",
            "control's protocol counters (rejections, duplicates, sent messages, …).",
            "event",
            counters,
        )
        yield _labelled(
            CounterMetricFamily,
            "fleet_control_vehicle_protocol_events",
            "Per-vehicle protocol counters summed over the fleet (gaps = header ids skipped: "
            "messages lost between vehicle and control).",
            "event",
            snapshot.get("vehicle_counters", {}),
        )
        yield from (
            _histogram(name, help_text, snapshot[key])
            for name, help_text, key in (
                (
                    "fleet_control_message_handling_seconds",
                    "Time control spends on one inbound message (decode to tracking).",
                    "handling_seconds",
                ),
                (
                    "fleet_control_state_to_order_seconds",
                    "From a state message's arrival to the order update it made control publish.",
                    "state_to_order_seconds",
                ),
                (
                    "fleet_control_state_age_seconds",
                    "A state message's age when control applied it (vehicle timestamp to "
                    "applied): the ingest lag, plus the vehicle's clock skew if any.",
                    "state_age_seconds",
                ),
                (
                    "fleet_control_gc_young_pause_seconds",
                    "Garbage collections of the young generations (0, 1) in control.",
                    "gc_young_pause_seconds",
                ),
                (
                    "fleet_control_gc_full_pause_seconds",
                    "Full garbage collections (generation 2) in control.",
                    "gc_full_pause_seconds",
                ),
                (
                    "fleet_control_wakeup_delay_seconds",
                    "How late a sleeping thread of control wakes up (waiting for the GIL or a "
                    "core): what a message waiting in control's socket waits too.",
                    "wakeup_delay_seconds",
                ),
            )
            if snapshot.get(key)
        )
        yield _labelled(
            GaugeMetricFamily,
            "fleet_control_vehicles",
            "Vehicles in control's live model by link.",
            "link",
            snapshot.get("vehicles_by_link", {}),
        )
        yield GaugeMetricFamily(
            "fleet_control_vehicles_executing",
            "Vehicles control is driving an order with.",
            snapshot.get("vehicles_executing", 0),
        )
        yield _labelled(
            GaugeMetricFamily,
            "fleet_control_traffic_safety",
            "Traffic's safety net now: wait-for cycles (deadlocks) and stalled vehicles (no "
            "progress along a whole wait-for chain for 60 s). Both must stay 0: alert on any.",
            "check",
            snapshot.get("traffic_safety", {}),
        )
        yield CounterMetricFamily(
            "fleet_control_cpu_seconds", "CPU time of the control process.", snapshot["cpu_seconds"]
        )


def _labelled(
    family: type[CounterMetricFamily] | type[GaugeMetricFamily],
    name: str,
    help_text: str,
    label: str,
    counts: dict[str, Any],
) -> CounterMetricFamily | GaugeMetricFamily:
    """A family with one sample per entry of `counts` (label value -> count), sorted."""
    metric = family(name, help_text, labels=[label])
    for value, count in sorted(counts.items()):
        metric.add_metric([value], count)
    return metric


def _histogram(name: str, help_text: str, data: dict[str, Any]) -> HistogramMetricFamily:
    running, buckets = 0, []
    for bound, count in zip([*data["bounds"], float("inf")], data["counts"], strict=True):
        running += count
        buckets.append(("+Inf" if bound == float("inf") else repr(float(bound)), running))
    family = HistogramMetricFamily(name, help_text)
    family.add_metric([], buckets, sum_value=data["sum"])
    return family


def render(collector: FleetCollector) -> bytes:
    """The Prometheus text exposition of `collector`."""
    registry = CollectorRegistry(auto_describe=False)
    registry.register(collector)
    return generate_latest(registry)


def _redis_figures() -> tuple[dict[str, Any] | None, dict[str, int | None]]:
    queues: dict[str, int | None] = {"celery": None, "control_commands": None}
    if not settings.REDIS_URL:
        return None, queues
    try:
        client = redis.Redis.from_url(settings.REDIS_URL, socket_timeout=2)
        raw = client.get(SNAPSHOT_KEY)
        queues = {"celery": client.llen(CELERY_QUEUE), "control_commands": client.llen(QUEUE_KEY)}
    except redis.RedisError:
        logger.warning("metrics: Redis unreachable", exc_info=True)
        return None, queues
    return (json.loads(raw) if raw else None), queues


@require_GET
def metrics(request: HttpRequest) -> HttpResponse:
    """Prometheus scrape endpoint (no login: network or bearer-token access, see above)."""
    if not scrape_allowed(request):
        return HttpResponse("Forbidden\n", status=403, content_type="text/plain")
    snapshot, queues = _redis_figures()
    vehicles = list(
        Vehicle.objects.values("connection", "operating_mode")
        .annotate(n=Count("pk"))
        .order_by("connection", "operating_mode")
    )
    orders = dict(
        TransportOrder.objects.values_list("status").annotate(n=Count("pk")).order_by("status")
    )
    body = render(FleetCollector(snapshot, vehicles, orders, queues, time.time()))
    return HttpResponse(body, content_type=CONTENT_TYPE_LATEST)
