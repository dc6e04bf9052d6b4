"""control's metrics writer lives as long as its term of leadership."""

import json
import threading

import pytest
import redis
from django.conf import settings

from control.controller import Controller
from control.metrics import SNAPSHOT_KEY, ControlMetrics, start_snapshots
from tests.control.fakes import FakeStore


@pytest.mark.skipif(not settings.REDIS_URL, reason="needs Redis")
def test_the_writer_stops_when_its_loop_has_finished() -> None:
    client = redis.Redis.from_url(settings.REDIS_URL)
    client.delete(SNAPSHOT_KEY)
    finished = threading.Event()
    metrics = ControlMetrics(Controller(store=FakeStore(), interface_name="uagv"))
    thread = start_snapshots(metrics, settings.REDIS_URL, interval=0.05, until=finished)
    assert thread is not None
    for _ in range(100):
        if client.get(SNAPSHOT_KEY):
            break
        finished.wait(0.05)
    assert json.loads(client.get(SNAPSHOT_KEY) or b"{}"), "the writer never wrote"
    finished.set()
    thread.join(timeout=2)
    assert not thread.is_alive()
    client.delete(SNAPSHOT_KEY)
    finished.wait(0.2)
    assert client.get(SNAPSHOT_KEY) is None, "a finished term still writes its figures"
