"""Health and readiness of `control` (issue 11 item 4): a tiny HTTP server and a leader heartbeat.

`GET /health` answers 200 while the process runs (liveness); `GET /ready` answers 200 only on the
leader with a running lease, a connected MQTT client and a reachable database, else 503 — a
standby is alive but not ready. Both return the role and fencing number as JSON. The server runs
on `CONTROL_HEALTH_PORT` (0 = off); more routes can be added to `HealthServer.routes`.

The leader also writes a heartbeat to Redis (`LEADER_KEY`, expiring after `HEARTBEAT_TTL`), which
the web process's `/ready` reads to tell whether some control process leads.
"""

import json
import logging
import threading
import time
from collections.abc import Callable
from http.server import BaseHTTPRequestHandler, ThreadingHTTPServer
from typing import Any

import redis
from django.conf import settings

logger = logging.getLogger(__name__)

LEADER_KEY = "fleet:control:leader"
HEARTBEAT_TTL = 10.0  # seconds a heartbeat stays valid
HEARTBEAT_EVERY = 2.0
ALL_INTERFACES = "0.0.0.0"  # noqa: S104 (probes come from the orchestrator, not localhost)

Route = Callable[[], tuple[int, dict[str, Any]]]


class HealthServer:
    """`/health` and `/ready` (and whatever else is put in `routes`) on a daemon thread."""

    def __init__(
        self, port: int, status: Callable[[], dict[str, Any]], host: str = ALL_INTERFACES
    ) -> None:
        self.status = status
        self.routes: dict[str, Route] = {"/health": self._health, "/ready": self._ready}
        routes = self.routes

        class Handler(BaseHTTPRequestHandler):
            def do_GET(self) -> None:  # noqa: N802 (http.server's name)
                route = routes.get(self.path.split("?", 1)[0])
                code, body = route() if route else (404, {"error": "not found"})
                data = json.dumps(body).encode()
                self.send_response(code)
                self.send_header("Content-Type", "application/json")
                self.send_header("Content-Length", str(len(data)))
                self.end_headers()
                self.wfile.write(data)

            def log_message(self, format: str, *args: Any) -> None:  # noqa: A002
                return  # probes every few seconds would flood the log

        self.server = _QuietServer((host, port), Handler)
        self.server.daemon_threads = True
        self.port = int(self.server.server_address[1])
        self._thread = threading.Thread(
            target=self.server.serve_forever, name="control-health", daemon=True
        )

    def start(self) -> "HealthServer":
        self._thread.start()
        return self

    def stop(self) -> None:
        self.server.shutdown()
        self.server.server_close()

    def _health(self) -> tuple[int, dict[str, Any]]:
        return 200, {"status": "ok", **self.status()}

    def _ready(self) -> tuple[int, dict[str, Any]]:
        status = self.status()
        return (200 if status.get("ready") else 503), status


class _QuietServer(ThreadingHTTPServer):
    def handle_error(self, request: Any, client_address: Any) -> None:
        # A probe that gave up (timeout) before the answer was written is no error of ours.
        logger.debug("health request from %s failed", client_address, exc_info=True)


def start_health_server(port: int, status: Callable[[], dict[str, Any]]) -> HealthServer | None:
    """The health server on `port`, or None when it is 0 or taken (logged, control still runs)."""
    if not port:
        return None
    try:
        server = HealthServer(port, status).start()
    except OSError as error:
        logger.error("health server: cannot listen on port %s (%s)", port, error)
        return None
    logger.info("health server on port %s (/health, /ready)", server.port)
    return server


def _redis() -> redis.Redis | None:
    if not settings.REDIS_URL:
        return None
    return redis.Redis.from_url(settings.REDIS_URL, socket_timeout=2, socket_connect_timeout=2)


class LeaderHeartbeat:
    """Writes the leader's status to Redis every few seconds while `status()` says ready."""

    def __init__(self, status: Callable[[], dict[str, Any]]) -> None:
        self.status = status
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, name="control-heartbeat", daemon=True)

    def start(self) -> "LeaderHeartbeat":
        if settings.REDIS_URL:
            self._thread.start()
        return self

    def stop(self) -> None:
        self._stop.set()

    def _run(self) -> None:
        client = _redis()
        while client is not None and not self._stop.wait(HEARTBEAT_EVERY):
            status = self.status()
            if not status.get("ready"):
                continue
            beat = {"fencing": status.get("fencing"), "identity": status.get("identity")}
            try:
                client.set(
                    LEADER_KEY,
                    json.dumps({**beat, "at": time.time()}),
                    px=int(HEARTBEAT_TTL * 1000),
                )
            except redis.RedisError:
                logger.warning("heartbeat: Redis unavailable", exc_info=False)


def read_leader_heartbeat() -> dict[str, Any] | None:
    """The latest leader heartbeat, or None when none is fresh (or there is no Redis)."""
    client = _redis()
    if client is None:
        return None
    raw = client.get(LEADER_KEY)
    if not isinstance(raw, bytes | str):
        return None
    beat: dict[str, Any] = json.loads(raw)
    if time.time() - float(beat.get("at", 0)) > HEARTBEAT_TTL:
        return None
    return beat
