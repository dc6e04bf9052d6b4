"""/metrics: what control counts, how it is rendered for Prometheus, and who may scrape it."""

import gc
import json
import logging
import threading
import time
from datetime import UTC, datetime, timedelta
from types import SimpleNamespace
from typing import Any

import msgspec
import pytest
import redis
from django.conf import settings
from django.test import Client
from prometheus_client.parser import text_string_to_metric_families

from control.controller import Controller
from control.metrics import SNAPSHOT_KEY, CauseLog, ControlMetrics, Histogram
from control.prometheus import FleetCollector, render
from fleet.logging import JsonFormatter
from robots.models import Vehicle
from tests.control.fakes import FakeStore, order, state, topic


def _samples(text: bytes) -> dict[tuple[str, tuple[tuple[str, str], ...]], float]:
    return {
        (s.name, tuple(sorted(s.labels.items()))): s.value
        for family in text_string_to_metric_families(text.decode())
        for s in family.samples
    }


def _instrumented(
    sent: list[tuple[str, bytes]], causes: CauseLog | None = None
) -> tuple[Controller, ControlMetrics, Any]:
    controller = Controller(
        store=FakeStore(orders=[order()]),
        interface_name="uagv",
        publish=lambda t, p, q: sent.append((t, p)),
        base_ahead=1,
    )
    controller.load()
    client = SimpleNamespace(
        on_message=lambda c, u, m: controller.handle_message(m.topic, bytes(m.payload))
    )
    link = SimpleNamespace(client=client, connected=threading.Event())
    metrics = ControlMetrics(controller)
    metrics.instrument(link, causes)  # type: ignore[arg-type]
    return controller, metrics, client


def test_the_cause_log_names_the_state_behind_each_order_update(tmp_path: Any) -> None:
    sent: list[tuple[str, bytes]] = []
    controller, metrics, client = _instrumented(sent, CauseLog(str(tmp_path / "causes.jsonl")))
    _deliver(client, topic(), state(last_node="a"))
    controller.sync(controller.store.active_orders())  # the order itself: no state behind it
    _deliver(client, topic(), state(header_id=2, order_id="TO-7", last_node="b"))

    (update,) = [json.loads(p) for t, p in sent if t.endswith("/order")][1:]
    lines = [json.loads(line) for line in (tmp_path / "causes.jsonl").read_text().splitlines()]
    assert lines == [
        {
            "order": topic(kind="order"),
            "orderId": update["orderId"],
            "orderUpdateId": update["orderUpdateId"],
            "state": topic(),
            "headerId": 2,
        }
    ]


def _deliver(client: Any, topic_text: str, payload: bytes) -> None:
    client.on_message(None, None, SimpleNamespace(topic=topic_text, payload=payload))


def test_histogram_buckets_by_upper_bound() -> None:
    histogram = Histogram((0.001, 0.01))
    for seconds in (0.0005, 0.001, 0.002, 5.0):
        histogram.observe(seconds)

    assert histogram.as_dict() == {"bounds": [0.001, 0.01], "counts": [2, 1, 1], "sum": 5.0035}


def test_messages_are_counted_by_topic_and_orders_sent_from_a_state_are_timed() -> None:
    sent: list[tuple[str, bytes]] = []
    controller, metrics, client = _instrumented(sent)
    _deliver(client, topic(), state(last_node="a"))
    controller.sync(controller.store.active_orders())  # the order itself: main thread, not timed
    assert [t for t, _ in sent if t.endswith("/order")]
    assert sum(metrics.state_to_order.counts) == 0

    # The vehicle reaches b: control releases the next node from the paho thread (an update).
    _deliver(client, topic(), state(header_id=2, order_id="TO-7", last_node="b"))  # b passed
    _deliver(client, topic(kind="visualization"), b"{not json")

    updates = [json.loads(p) for t, p in sent if t.endswith("/order")]
    assert updates[-1]["orderUpdateId"] >= 1
    assert sum(metrics.state_to_order.counts) == 1
    snapshot = metrics.snapshot()
    assert snapshot["messages_by_topic"] == {"state": 2, "visualization": 1}
    assert snapshot["counters"]["decode_errors"] == 1
    assert snapshot["vehicle_counters"]["decode_errors"] == 1  # the vehicle's own count too
    assert sum(snapshot["handling_seconds"]["counts"]) == 3
    assert snapshot["vehicles"] == 1
    assert snapshot["vehicles_executing"] == 1


def test_collections_and_late_wakeups_are_timed() -> None:
    _, metrics, _ = _instrumented([])
    until = threading.Event()
    probe = metrics.watch_pauses(until)
    try:
        gc.collect()  # a full collection
        gc.collect(0)
        time.sleep(0.25)  # the probe wakes up every 20 ms
    finally:
        until.set()
        probe.join(timeout=2.0)
    snapshot = metrics.snapshot()
    assert sum(snapshot["gc_full_pause_seconds"]["counts"]) >= 1
    assert sum(snapshot["gc_young_pause_seconds"]["counts"]) >= 1
    delays = snapshot["wakeup_delay_seconds"]
    assert sum(delays["counts"]) >= 5
    assert delays["sum"] >= 0.0
    assert metrics._on_gc not in gc.callbacks  # removed when the term ends
    full = sum(snapshot["gc_full_pause_seconds"]["counts"])
    gc.collect()
    assert sum(metrics.snapshot()["gc_full_pause_seconds"]["counts"]) == full


def test_rendering_has_counters_histograms_and_database_gauges() -> None:
    histogram = Histogram((0.001, 0.01))
    histogram.observe(0.0005)
    histogram.observe(0.02)
    snapshot = {
        "time": 1000.0,
        "broker_connected": True,
        "counters": {"messages": 7, "decode_errors": 2, "sent_order": 1},
        "vehicle_counters": {"gaps": 4},
        "messages_by_topic": {"state": 5, "visualization": 2},
        "handling_seconds": histogram.as_dict(),
        "state_to_order_seconds": Histogram((0.001,)).as_dict(),
        "wakeup_delay_seconds": histogram.as_dict(),
        "gc_full_pause_seconds": Histogram((0.1,)).as_dict(),
        "vehicles_by_link": {"ONLINE": 3},
        "vehicles_executing": 1,
        "traffic_safety": {"cycles": 0, "stalled": 2},
        "cpu_seconds": 12.5,
    }
    collector = FleetCollector(
        snapshot,
        [{"connection": "ONLINE", "operating_mode": "AUTOMATIC", "n": 3}],
        {"IN_PROGRESS": 2},
        {"celery": 4, "control_commands": 0},
        now=1005.0,
    )

    samples = _samples(render(collector))

    assert samples[("fleet_control_up", ())] == 1
    assert samples[("fleet_control_messages_received_total", (("topic", "state"),))] == 5
    assert samples[("fleet_control_decode_errors_total", ())] == 2
    assert samples[("fleet_control_events_total", (("event", "sent_order"),))] == 1
    gaps = ("fleet_control_vehicle_protocol_events_total", (("event", "gaps"),))
    assert samples[gaps] == 4
    bucket = "fleet_control_message_handling_seconds_bucket"
    assert samples[(bucket, (("le", "0.001"),))] == 1
    assert samples[(bucket, (("le", "+Inf"),))] == 2
    assert samples[("fleet_control_message_handling_seconds_count", ())] == 2
    assert samples[("fleet_control_wakeup_delay_seconds_count", ())] == 2
    assert samples[("fleet_control_gc_full_pause_seconds_count", ())] == 0
    assert ("fleet_control_gc_young_pause_seconds_count", ()) not in samples  # not in snapshot
    assert samples[("fleet_control_vehicles", (("link", "ONLINE"),))] == 3
    assert samples[("fleet_control_traffic_safety", (("check", "stalled"),))] == 2
    assert samples[("fleet_control_traffic_safety", (("check", "cycles"),))] == 0
    key = (("connection", "ONLINE"), ("operating_mode", "AUTOMATIC"))
    assert samples[("fleet_vehicles", key)] == 3
    assert samples[("fleet_transport_orders", (("status", "IN_PROGRESS"),))] == 2
    assert samples[("fleet_transport_orders", (("status", "FINISHED"),))] == 0
    assert samples[("fleet_queue_length", (("queue", "celery"),))] == 4


def test_a_stale_snapshot_reports_control_down_and_nothing_else_of_it() -> None:
    collector = FleetCollector({"time": 1000.0}, [], {}, {}, now=1016.0)

    samples = _samples(render(collector))

    assert samples[("fleet_control_up", ())] == 0
    assert not any(name.startswith("fleet_control_messages") for name, _ in samples)


@pytest.mark.django_db
def test_anonymous_scrapes_only_from_allowed_networks(settings: Any) -> None:
    Vehicle.objects.create(manufacturer="sim", serial_number="AGV-1", connection="ONLINE")
    settings.METRICS_ALLOWED_CIDRS = ["127.0.0.1/32"]

    local = Client(REMOTE_ADDR="127.0.0.1").get("/metrics")
    remote = Client(REMOTE_ADDR="10.1.2.3").get("/metrics")
    settings.METRICS_ALLOWED_CIDRS = ["10.1.0.0/16"]
    remote_allowed = Client(REMOTE_ADDR="10.1.2.3").get("/metrics")

    assert local.status_code == 200
    assert local["Content-Type"].startswith("text/plain; version=")
    assert b'fleet_vehicles{connection="ONLINE",operating_mode="UNKNOWN"} 1.0' in local.content
    assert remote.status_code == 403
    assert remote_allowed.status_code == 200


@pytest.mark.django_db
def test_a_bearer_token_opens_metrics_from_anywhere_and_a_wrong_one_does_not(
    settings: Any,
) -> None:
    settings.METRICS_ALLOWED_CIDRS = ["127.0.0.1/32"]
    settings.METRICS_TOKEN = "s3cret-token"
    remote = Client(REMOTE_ADDR="10.1.2.3")

    assert remote.get("/metrics", HTTP_AUTHORIZATION="Bearer s3cret-token").status_code == 200
    assert remote.get("/metrics", HTTP_AUTHORIZATION="Bearer wrong").status_code == 403
    # A wrong token does not fall back to the address check either.
    local = Client(REMOTE_ADDR="127.0.0.1")
    assert local.get("/metrics", HTTP_AUTHORIZATION="Bearer wrong").status_code == 403
    settings.METRICS_TOKEN = ""
    assert remote.get("/metrics", HTTP_AUTHORIZATION="Bearer ").status_code == 403
    assert Client(REMOTE_ADDR="127.0.0.1").post("/metrics").status_code == 405  # GET only


@pytest.mark.django_db
def test_the_control_snapshot_in_redis_is_rendered() -> None:
    if not settings.REDIS_URL:
        pytest.skip("needs Redis")
    client = redis.Redis.from_url(settings.REDIS_URL)
    snapshot = {
        "time": time.time(),
        "broker_connected": True,
        "counters": {"messages": 3},
        "messages_by_topic": {"state": 3},
        "handling_seconds": Histogram().as_dict(),
        "state_to_order_seconds": Histogram().as_dict(),
        "vehicles_by_link": {},
        "vehicles_executing": 0,
        "cpu_seconds": 1.0,
    }
    client.set(SNAPSHOT_KEY, json.dumps(snapshot))
    try:
        response = Client().get("/metrics")
    finally:
        client.delete(SNAPSHOT_KEY)

    samples = _samples(response.content)
    assert samples[("fleet_control_up", ())] == 1
    assert samples[("fleet_control_messages_received_total", (("topic", "state"),))] == 3
    assert ("fleet_queue_length", (("queue", "control_commands"),)) in samples


def test_json_log_lines_carry_level_logger_message_extras_and_exceptions() -> None:
    record = logging.LogRecord("control.runner", logging.ERROR, __file__, 1, "x=%d", (5,), None)
    record.vehicle = "AGV-1"
    try:
        raise ValueError("boom")
    except ValueError:
        import sys

        record.exc_info = sys.exc_info()

    line = json.loads(JsonFormatter().format(record))

    assert line["level"] == "ERROR"
    assert line["logger"] == "control.runner"
    assert line["message"] == "x=5"
    assert line["vehicle"] == "AGV-1"
    assert "ValueError: boom" in line["exception"]
    assert line["time"].endswith("+00:00")


def test_a_state_s_age_when_applied_is_the_ingest_lag() -> None:
    _, metrics, client = _instrumented([])
    stamped = datetime.now(UTC) - timedelta(seconds=0.3)
    message = msgspec.json.decode(state(last_node="a"))
    message["timestamp"] = stamped.isoformat().replace("+00:00", "Z")
    _deliver(client, topic(), msgspec.json.encode(message))
    _deliver(client, topic(kind="visualization"), b"{not json")  # no state: no age

    age = metrics.snapshot()["state_age_seconds"]
    by_bound = dict(zip([*age["bounds"], "inf"], age["counts"], strict=True))
    assert sum(age["counts"]) == 1
    assert by_bound[0.5] == 1  # 0.3 s and the time to handle it
    snapshot = metrics.snapshot()
    rendered = _samples(render(FleetCollector(snapshot, [], {}, {}, now=snapshot["time"])))
    assert rendered[("fleet_control_state_age_seconds_count", ())] == 1
