"""control's browser broadcasts on one long-lived event loop of their own.

`fleet.realtime` sends from a thread without an event loop through `async_to_sync`, which
builds a new event loop per call, and channels_redis keeps its connections per loop: every
broadcast (control's live snapshot 5 times a second, each order change) opened a new Redis
connection and waited for it on control's main loop, about a tenth of control's samples in the
load bench (docs/LOAD.md). Here one daemon thread runs a loop for the whole process and
registers it with `fleet.realtime` (as the web process does with its own), so a broadcast is
handed over without waiting, over connections that stay open.

Sends are serialised in the order they were handed over: the live page gets only the changes
(`control.snapshots.LiveDeltas`), so two snapshots must not overtake each other.

After a Redis loss the loop goes on by itself: sends fail while Redis is away and the next one
after it returns opens a new connection (bench/faults redis row: no restart of control).

Whether anyone watches: `LiveAudience` tells control whether a browser has the live page open
(the consumers keep `LiveViewer` marks), so that control builds no rows for nobody.
"""

import asyncio
import logging
import threading
import time
from collections.abc import Awaitable, Callable
from typing import Any

import redis
import redis.asyncio as aioredis
from channels.layers import InMemoryChannelLayer, get_channel_layer
from django.conf import settings

from fleet import realtime

logger = logging.getLogger(__name__)

SEND_TIMEOUT_S = 5.0
_started: list[asyncio.AbstractEventLoop] = []  # the process's loop once started
_lock = threading.Lock()


def start() -> asyncio.AbstractEventLoop | None:
    """Start the broadcast loop once per process (later calls return it); None when the layer
    is the in-memory one (the embedded demo: the web process's own loop serves it)."""
    layer = get_channel_layer()
    if layer is None or isinstance(layer, InMemoryChannelLayer):
        return None
    with _lock:
        if _started:
            return _started[0]
        loop = asyncio.new_event_loop()
        ready = threading.Event()
        layer.group_send = _in_order(layer.group_send)

        async def register() -> None:
            realtime.remember_web_loop()  # realtime._send now hands sends to this loop
            ready.set()

        def run() -> None:
            asyncio.set_event_loop(loop)
            loop.run_until_complete(register())
            loop.run_forever()

        threading.Thread(target=run, name="control-broadcasts", daemon=True).start()
        ready.wait(5)
        _started.append(loop)
        return loop


def _in_order(
    group_send: Callable[[str, dict[str, Any]], Awaitable[None]],
) -> Callable[[str, dict[str, Any]], Awaitable[None]]:
    """`group_send` one at a time: asyncio.Lock wakes its waiters first come, first served.

    Each send gets SEND_TIMEOUT_S: the layer's sockets have no read timeout (settings), so a
    send stuck on a Redis that stopped answering would otherwise hold up every later one for
    good. A failed send fails alone (fleet.realtime logs it) and the next one reconnects."""
    turn = asyncio.Lock()

    async def send(group: str, message: dict[str, Any]) -> None:
        async with turn:
            await asyncio.wait_for(group_send(group, message), SEND_TIMEOUT_S)

    return send


# -- who watches: the live page's presence ----------------------------------------------------
#
# control builds its live rows only while a browser has the live page open: 1,000 moving
# vehicles cost a few per cent of a core 5 times a second, for nobody otherwise. Each live
# websocket's consumer (control.consumers) marks its channel as watching every HEARTBEAT_S,
# valid for VIEWER_TTL_S, so a web process that died without saying goodbye stops counting.
# With REDIS_URL the marks are a Redis sorted set (channel -> valid until, in Unix seconds:
# web and control run on hosts with synchronised clocks); without it (the embedded demo, where
# control runs in the web process) a dict in this process.

VIEWERS_KEY = "fleet:live:viewers"
HEARTBEAT_S = 2.0
VIEWER_TTL_S = 10.0
RECHECK_S = 1.0  # while a page is open control asks again at most this often
AFTER_ERROR_S = 5.0  # Redis unreadable: count as watched (build, as before) for this long
_local_viewers: dict[str, float] = {}  # channel name -> valid until (Unix seconds)


class LiveAudience:
    """Answers control's "is anyone watching the live page?" before each broadcast."""

    def __init__(self) -> None:
        self._client: redis.Redis | None = None
        self._client_url = ""
        self._watched_until = 0.0  # monotonic: a yes is trusted this long
        self._failing = False

    def watching(self) -> bool:
        """True while a live page is open, or while that cannot be told (errors: never raises,
        control's loop calls it unguarded)."""
        now = time.monotonic()
        if now < self._watched_until:
            return True
        try:
            watched = self._count_viewers() > 0
        except Exception as error:
            if not self._failing:
                logger.warning("cannot tell whether a live page is open (%r); building rows", error)
            self._failing = True
            self._watched_until = now + AFTER_ERROR_S
            return True
        self._failing = False
        if watched:
            self._watched_until = now + RECHECK_S
        return watched

    def _count_viewers(self) -> int:
        url = settings.REDIS_URL
        if not url:
            now = time.time()
            return sum(1 for until in list(_local_viewers.values()) if until > now)
        if self._client is None or self._client_url != url:
            # Short timeouts: this runs on control's main loop, and a hung Redis must not hold it.
            self._client = redis.Redis.from_url(url, socket_timeout=0.2, socket_connect_timeout=0.2)
            self._client_url = url
        return int(self._client.zcount(VIEWERS_KEY, time.time(), "+inf"))


LIVE_AUDIENCE = LiveAudience()


class LiveViewer:
    """One live websocket's mark in the audience, kept fresh by its consumer while it is open."""

    def __init__(self, channel_name: str) -> None:
        self.channel_name = channel_name
        url = settings.REDIS_URL
        self._client = aioredis.Redis.from_url(url, socket_timeout=2) if url else None

    async def mark(self) -> None:
        """Mark the channel as watching for VIEWER_TTL_S. A failure is only logged: control
        builds its rows anyway while it cannot read Redis, and the next heartbeat tries again."""
        try:
            await self._mark(time.time() + VIEWER_TTL_S)
        except Exception as error:
            logger.debug("live page presence not marked: %r", error)

    async def keep(self) -> None:
        """Renew the mark every HEARTBEAT_S until cancelled."""
        while True:
            await asyncio.sleep(HEARTBEAT_S)
            await self.mark()

    async def end(self) -> None:
        """Remove the mark (the websocket closed)."""
        try:
            await self._mark(None)
        except Exception as error:  # it expires by itself after VIEWER_TTL_S
            logger.debug("live page presence not removed: %r", error)
        finally:
            if self._client is not None:
                await self._client.aclose()

    async def _mark(self, until: float | None) -> None:
        if self._client is None:
            if until is None:
                _local_viewers.pop(self.channel_name, None)
            else:
                _local_viewers[self.channel_name] = until
            return
        if until is None:
            await self._client.zrem(VIEWERS_KEY, self.channel_name)
            return
        async with self._client.pipeline(transaction=False) as pipe:
            pipe.zadd(VIEWERS_KEY, {self.channel_name: until})
            pipe.zremrangebyscore(VIEWERS_KEY, "-inf", time.time())  # marks of dead processes
            pipe.expire(VIEWERS_KEY, int(VIEWER_TTL_S) + 1)
            await pipe.execute()
