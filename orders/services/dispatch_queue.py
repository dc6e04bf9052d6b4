"""Waking dispatch: one queued dispatch cycle at a time, however many writes ask for one.

Every new order, finished order and newly available vehicle asks for a dispatch cycle. Queuing a
task per request made them wait behind each other on the cycle's advisory lock under load (a
cycle reads all pending orders anyway, so one queued cycle serves every request made before it
starts). With Redis a flag records that a cycle is queued and not yet started: a request sets it
with SET NX and queues a task only when it was not set; the task clears it first thing, so a
request made while a cycle runs queues exactly one more. The flag expires on its own (FLAG_TTL)
in case its task is lost; beat also runs dispatch periodically.

Without Redis (the embedded demo: eager tasks, no broker) or when Redis fails, every request
queues a task as before: a dispatch request is never dropped.
"""

import logging
from functools import lru_cache

import redis
from django.conf import settings

logger = logging.getLogger(__name__)

FLAG_KEY = "fleet:dispatch:requested"
FLAG_TTL = 30  # seconds; a lost task delays dispatch at most this long (beat runs it sooner)


@lru_cache(maxsize=4)
def _client_for(url: str) -> redis.Redis:
    # One connection pool per process and URL: a request costs one round trip, no new connection.
    return redis.Redis.from_url(url, socket_timeout=1, socket_connect_timeout=1)


def _client() -> redis.Redis | None:
    return _client_for(settings.REDIS_URL) if settings.REDIS_URL else None


def request_dispatch() -> None:
    """Queue a dispatch cycle unless one is already queued and has not started yet.

    Raises what queuing the task raises (the broker is down); callers log it, beat runs dispatch
    anyway. The flag is then cleared so the next request tries to queue again.
    """
    from orders.tasks import dispatch_pending_orders_task

    client = _client()
    if client is not None:
        try:
            if not client.set(FLAG_KEY, "1", nx=True, ex=FLAG_TTL):
                return  # the queued cycle has not started: it will read this change too
        except redis.RedisError:
            logger.warning("could not check the dispatch flag; queuing dispatch anyway")
            client = None
    try:
        dispatch_pending_orders_task.delay()
    except Exception:
        if client is not None:
            _clear(client)
        raise


def start_cycle() -> None:
    """Mark the queued cycle as started (the dispatch task calls this first): requests from now
    on queue one more cycle, since this one may already have read the pending orders."""
    client = _client()
    if client is not None:
        _clear(client)


def _clear(client: redis.Redis) -> None:
    try:
        client.delete(FLAG_KEY)
    except redis.RedisError:
        logger.warning("could not clear the dispatch flag; it expires in %d s", FLAG_TTL)
