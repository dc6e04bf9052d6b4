"""The command queue from web and Celery to the `control` process.

The database stays the source of truth (an assigned transport order is a row); a command only
wakes `control` up so it acts at once instead of at its next periodic sync. With REDIS_URL the
queue is a Redis list shared by all processes; without it (embedded demo, where `control` runs in
the web process) it is an in-process queue.
"""

import json
import logging
import queue
from functools import lru_cache
from typing import Any

import redis
from django.conf import settings

logger = logging.getLogger(__name__)

QUEUE_KEY = "fleet:control:commands"
_local_queue: "queue.Queue[dict[str, Any]]" = queue.Queue()


@lru_cache(maxsize=4)
def _client_for(url: str) -> redis.Redis:
    # One connection pool per process and URL: a command costs one round trip, not a new TCP
    # connection (control polls between its periodic steps, so this adds up).
    return redis.Redis.from_url(url, socket_timeout=5)


def _redis() -> redis.Redis | None:
    return _client_for(settings.REDIS_URL) if settings.REDIS_URL else None


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
    """Wait up to `timeout` seconds for commands and return all that are queued (for `control`);
    with `timeout` <= 0 only take what is queued now, without waiting."""
    client = _redis()
    if client is None:
        return _drain_local(timeout)
    if timeout > 0:
        first = client.brpop([QUEUE_KEY], timeout=timeout)  # Redis >= 6 takes fractions
        if first is None:
            return []
        raw: list[bytes | str] = [first[1]]
    else:  # BRPOP would read 0 as "wait forever"
        raw = []
    while isinstance(more := client.rpop(QUEUE_KEY), bytes | str):
        raw.append(more)
    return [_parse(item) for item in raw if item]


def _drain_local(timeout: float) -> list[dict[str, Any]]:
    commands: list[dict[str, Any]] = []
    if timeout > 0:
        try:
            commands.append(_local_queue.get(timeout=timeout))
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
