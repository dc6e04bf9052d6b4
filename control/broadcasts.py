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
"""

import asyncio
import logging
import threading
from collections.abc import Awaitable, Callable
from typing import Any

from channels.layers import InMemoryChannelLayer, get_channel_layer

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
