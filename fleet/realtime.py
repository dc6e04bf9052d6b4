"""Broadcasts to browsers over the Channels layer; domain code sends only through these."""

import asyncio
import logging
from collections.abc import Mapping
from typing import Any

from asgiref.sync import async_to_sync
from channels.layers import get_channel_layer
from django.db import transaction

logger = logging.getLogger(__name__)

LIVE_GROUP = "live"
_web_loop: asyncio.AbstractEventLoop | None = None


def remember_web_loop() -> None:
    """Called by consumers: the event loop that serves websockets in this process.

    The in-memory channel layer (embedded demo, where `control` runs inside the web process) is
    not thread-safe, so sends from other threads are handed to this loop instead of running on
    a private loop of their own.
    """
    global _web_loop
    _web_loop = asyncio.get_running_loop()


def broadcast(group: str, event_type: str, payload: Mapping[str, Any]) -> None:
    """Send `payload` to every websocket in `group` now; a failing layer only logs."""
    layer = get_channel_layer()
    if layer is None:
        return
    message = {"type": "fleet.event", "event": event_type, "payload": dict(payload)}
    try:
        loop = _web_loop
        if loop is not None and not loop.is_closed() and not _running_on(loop):
            asyncio.run_coroutine_threadsafe(layer.group_send(group, message), loop)
        else:
            async_to_sync(layer.group_send)(group, message)
    except Exception:  # a broken channel layer must never break the caller
        logger.exception("broadcast to %s failed", group)


def broadcast_on_commit(group: str, event_type: str, payload: Mapping[str, Any]) -> None:
    """Send `payload` to a Channels group once the current transaction commits."""
    data = dict(payload)
    transaction.on_commit(lambda: broadcast(group, event_type, data))


def _running_on(loop: asyncio.AbstractEventLoop) -> bool:
    try:
        return asyncio.get_running_loop() is loop
    except RuntimeError:
        return False
