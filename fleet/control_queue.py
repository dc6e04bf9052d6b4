"""The command queue from web and Celery to the `control` process.

The database stays the source of truth (an assigned transport order is a row); a command only
wakes `control` up so it acts at once instead of at its next periodic sync. With REDIS_URL the
queue is a Redis list shared by all processes; without it (embedded demo, where `control` runs in
the web process) it is an in-process queue.
"""

import json
import logging
import queue
from typing import Any

import redis
from django.conf import settings

logger = logging.getLogger(__name__)

QUEUE_KEY = "fleet:control:commands"
_local_queue: "queue.Queue[dict[str, Any]]" = queue.Queue()


def _redis() -> redis.Redis | None:
    if not settings.REDIS_URL:
        return None
    return redis.Redis.from_url(settings.REDIS_URL, socket_timeout=5)


def send_command(kind: str, **payload: Any) -> None:
    """Queue a command for `control`; failure is logged, since `control` also syncs periodically."""
    command = {"kind": kind, **payload}
    client = _redis()
    if client is None:
        _local_queue.put(command)
        return
    try:
        client.lpush(QUEUE_KEY, json.dumps(command))
    except redis.RedisError:
        logger.warning("could not queue %s for control; it will pick it up on its next sync", kind)


def receive_commands(timeout: float) -> list[dict[str, Any]]:
    """Wait up to `timeout` seconds for commands and return all that are queued (for `control`)."""
    client = _redis()
    if client is None:
        return _drain_local(timeout)
    first = client.brpop([QUEUE_KEY], timeout=timeout)  # Redis >= 6 takes fractions
    if first is None:
        return []
    raw: list[bytes | str] = [first[1]]
    while isinstance(more := client.rpop(QUEUE_KEY), bytes | str):
        raw.append(more)
    return [_parse(item) for item in raw if item]


def _drain_local(timeout: float) -> list[dict[str, Any]]:
    try:
        commands = [_local_queue.get(timeout=timeout)]
    except queue.Empty:
        return []
    while True:
        try:
            commands.append(_local_queue.get_nowait())
        except queue.Empty:
            return commands


def _parse(raw: bytes | str) -> dict[str, Any]:
    try:
        value = json.loads(raw)
    except ValueError:
        logger.warning("dropped a malformed control command: %r", raw[:200])
        return {"kind": "invalid"}
    return value if isinstance(value, dict) else {"kind": "invalid"}
