"""Broadcasts to browsers over the Channels layer; domain code sends only through these."""

import asyncio
import logging
import math
from collections.abc import Mapping
from concurrent.futures import Future
from typing import Any

import msgspec
from asgiref.sync import async_to_sync
from channels.layers import get_channel_layer
from django.db import transaction

logger = logging.getLogger(__name__)

LIVE_GROUP = "live"


def vehicle_group(pk: int) -> str:
    """The group of the open pages of one vehicle (its raw VDA 5050 messages)."""
    return f"vehicle.{pk}"


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
    _send(layer, group, {"type": "fleet.event", "event": event_type, "payload": dict(payload)})


# Daphne (autobahn) closes a websocket whose outgoing message exceeds 1 MiB (code 1011): the
# live page's keyframe of 750 vehicles driving, with their routes, was 1.06 MB in a load run.
MAX_EVENT_BYTES = 512 * 1024


def broadcast_json(group: str, event_type: str, payload: Mapping[str, list[Any]]) -> None:
    """Like `broadcast`, but the event is encoded to JSON once, here, and every consumer
    forwards the text as it is (`fleet.json` messages). For large, frequent events (control's
    vehicle snapshots: 1,000 vehicles 5 times a second), where encoding per browser and packing
    the nested rows for the channel layer would dominate the fan-out cost. The payload's
    values are lists of items a page takes one by one: an event over MAX_EVENT_BYTES goes out
    as several, each with a share of every list (`encode_events`)."""
    for text in encode_events(event_type, payload):
        send_encoded(group, text)


def encode_event(event_type: str, payload: Mapping[str, Any]) -> str:
    """The websocket text of an event, as the consumers send it."""
    return msgspec.json.encode({"event": event_type, "payload": payload}).decode()


def encode_events(
    event_type: str, payload: Mapping[str, list[Any]], limit: int = MAX_EVENT_BYTES
) -> list[str]:
    """The event as one text, or as several of at most `limit` bytes (an item larger than
    that goes alone) that split every list of `payload` in order."""
    data = msgspec.json.encode({"event": event_type, "payload": payload})
    longest = max((len(items) for items in payload.values()), default=0)
    if len(data) <= limit or longest <= 1:
        return [data.decode()]
    parts = min(longest, math.ceil(len(data) * 1.1 / limit))
    texts: list[str] = []
    for part in range(parts):
        share = {
            key: items[len(items) * part // parts : len(items) * (part + 1) // parts]
            for key, items in payload.items()
        }
        texts += encode_events(event_type, share, limit)
    return texts


def send_encoded(group: str, text: str) -> None:
    """Send an event encoded by `encode_event` to every websocket in `group` now."""
    layer = get_channel_layer()
    if layer is not None:
        _send(layer, group, {"type": "fleet.json", "text": text})


def _send(layer: Any, group: str, message: dict[str, Any]) -> None:
    try:
        loop = _web_loop
        if loop is not None and not loop.is_closed() and not _running_on(loop):
            future = asyncio.run_coroutine_threadsafe(layer.group_send(group, message), loop)
            future.add_done_callback(_outages.sent)
        else:
            async_to_sync(layer.group_send)(group, message)
    except Exception:  # a broken channel layer must never break the caller
        logger.exception("broadcast to %s failed", group)


class _Outages:
    """Logs sends handed to the loop that failed (nobody awaits them): the first of a run of
    failures and the recovery, not each of control's 5 broadcasts a second while Redis is down.
    The channel layer itself reconnects on the next send (the retry in settings.CHANNEL_LAYERS).
    """

    def __init__(self) -> None:
        self.failed = 0

    def sent(self, future: Future[None]) -> None:
        error = None if future.cancelled() else future.exception()
        if error is None:
            if self.failed:
                logger.warning("broadcasts recovered after %d failed sends", self.failed)
            self.failed = 0
            return
        if not self.failed:
            logger.error("broadcasts failing: %r", error)
        self.failed += 1


_outages = _Outages()


def broadcast_on_commit(group: str, event_type: str, payload: Mapping[str, Any]) -> None:
    """Send `payload` to a Channels group once the current transaction commits."""
    data = dict(payload)
    transaction.on_commit(lambda: broadcast(group, event_type, data))


def _running_on(loop: asyncio.AbstractEventLoop) -> bool:
    try:
        return asyncio.get_running_loop() is loop
    except RuntimeError:
        return False
