"""control's broadcast loop after a Redis loss (RELIABILITY.md §3 row 11): against a
redis-server of the test's own (SIGKILLed and restarted), with the channel layer configured as
in settings, broadcasts fail while Redis is away and arrive again once it is back, on the same
loop, without restarting anything."""

import asyncio
import logging
import shutil
import signal
import threading
import time
from collections.abc import Iterator
from pathlib import Path
from typing import Any, cast

import pytest
from channels_redis.core import RedisChannelLayer
from django.conf import settings

from bench.faults.stack import Redis
from control import broadcasts
from fleet import realtime


@pytest.fixture
def redis_server(tmp_path: Path) -> Iterator[Redis]:
    if shutil.which("redis-server") is None:
        pytest.skip("needs redis-server")
    server = Redis(tmp_path)
    server.start()
    yield server
    server.stop()


def _layer(url: str) -> RedisChannelLayer:
    """A channel layer like settings.CHANNEL_LAYERS' (its retry included), on `url`."""
    if "channels_redis" not in settings.CHANNEL_LAYERS["default"]["BACKEND"]:
        pytest.skip("needs REDIS_URL (the Redis channel layer settings)")
    config = dict(cast(dict[str, Any], settings.CHANNEL_LAYERS["default"]["CONFIG"]))
    config["hosts"] = [{**config["hosts"][0], "address": url}]
    return RedisChannelLayer(**config)


class Browser:
    """A websocket's side of the layer: its channel in the live group, on a loop of its own."""

    def __init__(self, url: str) -> None:
        self.layer = _layer(url)
        self.loop = asyncio.new_event_loop()
        threading.Thread(target=self.loop.run_forever, daemon=True).start()
        self.channel = self._run(self.layer.new_channel())

    def _run(self, coroutine: Any, timeout: float = 10) -> Any:
        return asyncio.run_coroutine_threadsafe(coroutine, self.loop).result(timeout)

    def join(self) -> None:
        """What LiveConsumer.connect does (again after a reconnect)."""
        self._run(self.layer.group_add(realtime.LIVE_GROUP, self.channel))

    def received(self, timeout: float) -> dict[str, Any] | None:
        try:
            message: dict[str, Any] = self._run(
                asyncio.wait_for(self.layer.receive(self.channel), timeout)
            )
            return message
        except TimeoutError:
            return None

    def close(self) -> None:
        self._run(self.layer.close_pools())
        self.loop.call_soon_threadsafe(self.loop.stop)


@pytest.fixture
def control_loop(
    redis_server: Redis, monkeypatch: pytest.MonkeyPatch
) -> Iterator[RedisChannelLayer]:
    """control's broadcast loop as control.broadcasts.start() builds it, on the test's Redis."""
    layer = _layer(redis_server.url)
    layer.group_send = broadcasts._in_order(layer.group_send)
    loop = asyncio.new_event_loop()
    threading.Thread(target=loop.run_forever, daemon=True).start()
    monkeypatch.setattr(realtime, "_web_loop", loop)
    yield layer
    asyncio.run_coroutine_threadsafe(layer.close_pools(), loop).result(10)
    loop.call_soon_threadsafe(loop.stop)


def _broadcast_until_received(layer: RedisChannelLayer, browser: Browser, timeout: float) -> float:
    started = time.monotonic()
    while time.monotonic() - started < timeout:
        realtime._send(layer, realtime.LIVE_GROUP, {"type": "fleet.json", "text": "x"})
        if browser.received(0.5) is not None:
            return time.monotonic() - started
    raise AssertionError(f"no broadcast arrived within {timeout} s")


def _logged_until(caplog: pytest.LogCaptureFixture, prefix: str, timeout: float) -> list[str]:
    """The captured messages, once one starts with `prefix` or `timeout` has passed."""
    deadline = time.monotonic() + timeout
    while True:
        messages = [r.getMessage() for r in caplog.records]
        if any(m.startswith(prefix) for m in messages) or time.monotonic() > deadline:
            return messages
        time.sleep(0.05)


def test_control_broadcasts_arrive_again_after_redis_is_killed_and_restarted(
    redis_server: Redis, control_loop: RedisChannelLayer, caplog: pytest.LogCaptureFixture
) -> None:
    browser = Browser(redis_server.url)
    try:
        browser.join()
        _broadcast_until_received(control_loop, browser, 5)

        with caplog.at_level(logging.WARNING, logger="fleet.realtime"):
            redis_server.signal(signal.SIGKILL)
            for _ in range(5):  # control's snapshots go on while Redis is away
                realtime._send(control_loop, realtime.LIVE_GROUP, {"type": "fleet.json"})
                time.sleep(0.2)
            redis_server.start()
            browser.join()  # the page reconnects and its consumer joins the group again
            recovered = _broadcast_until_received(control_loop, browser, 10)
            # The recovery is logged by the send's done-callback, on control's loop: it can
            # come a moment after the browser has the message on a busy machine.
            messages = _logged_until(caplog, "broadcasts recovered after", timeout=5)

        assert recovered < 5
        assert sum(m.startswith("broadcasts failing") for m in messages) == 1  # not one per send
        assert any(m.startswith("broadcasts recovered after") for m in messages)
    finally:
        browser.close()


def test_a_send_that_never_returns_does_not_hold_up_the_ones_behind_it(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    monkeypatch.setattr(broadcasts, "SEND_TIMEOUT_S", 0.1)
    arrived: list[int] = []

    async def group_send(group: str, message: dict[str, int]) -> None:
        if message["n"] == 0:
            await asyncio.Event().wait()  # a Redis that stopped answering
        arrived.append(message["n"])

    send = broadcasts._in_order(group_send)

    async def main() -> list[Any]:
        return await asyncio.gather(
            *(send("live", {"n": n}) for n in range(3)), return_exceptions=True
        )

    results = asyncio.run(main())
    assert isinstance(results[0], TimeoutError)
    assert arrived == [1, 2]
