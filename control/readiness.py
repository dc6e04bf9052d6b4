"""Readiness of the web process (issue 11 item 4): database, Redis and a leading `control`.

`/health` says the web process runs; `/ready` says it can do its work: the database answers,
Redis answers (Celery broker, channel layer, command queue), and some `control` process has led
within the last `control.health.HEARTBEAT_TTL` seconds (its heartbeat in Redis). Without Redis
(the embedded demo) `control` runs inside the web process, so there is no heartbeat to check.
"""

from typing import Any

import redis
from django.conf import settings
from django.db import connection

from control.health import read_leader_heartbeat


def web_readiness() -> dict[str, Any]:
    """Each check as `ok` or the reason it failed, and `ready` when all passed."""
    checks: dict[str, Any] = {
        "database": _check(_database),
        "redis": "not used",
        "control": "in process",
    }
    if settings.REDIS_URL:
        checks["redis"] = _check(_redis)
        checks["control"] = _check(_control)
    ready = all(value == "ok" or value in {"not used", "in process"} for value in checks.values())
    return {"ready": ready, **checks}


def _check(probe: Any) -> str:
    try:
        return str(probe())
    except Exception as error:  # any failure makes the process not ready, with the reason
        return f"failed: {type(error).__name__}: {error}"[:200]


def _database() -> str:
    with connection.cursor() as cursor:
        cursor.execute("SELECT 1")
    return "ok"


def _redis() -> str:
    client = redis.Redis.from_url(settings.REDIS_URL, socket_timeout=2, socket_connect_timeout=2)
    client.ping()
    return "ok"


def _control() -> str:
    beat = read_leader_heartbeat()
    if beat is None:
        return "failed: no control process has led recently"
    return "ok"
