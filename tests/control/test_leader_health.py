"""Health and readiness (issue 11 item 4): control's /health and /ready by role, the web
process's /ready over database, Redis and the leader heartbeat."""

import json
import os
import subprocess
import sys
import time
import urllib.error
import urllib.request
import uuid
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest
import redis
from django.conf import settings
from django.test import Client

from control import health
from control.health import LEADER_KEY, HealthServer
from control.standby import StandbyControl
from tests.e2e.processes import ROOT, Process, wait_until


def get(port: int, path: str) -> tuple[int, dict[str, Any]]:
    try:
        with urllib.request.urlopen(f"http://127.0.0.1:{port}{path}", timeout=5) as response:  # noqa: S310
            return response.status, json.loads(response.read())
    except urllib.error.HTTPError as error:
        return error.code, json.loads(error.read())


def test_control_health_is_alive_for_both_roles_and_ready_only_for_a_connected_leader() -> None:
    status: dict[str, Any] = {"role": "standby", "fencing": None, "ready": False}
    server = HealthServer(0, lambda: dict(status), host="127.0.0.1").start()
    try:
        assert get(server.port, "/health") == (200, {"status": "ok", **status})
        code, body = get(server.port, "/ready")
        assert code == 503
        assert body["role"] == "standby"

        status.update(role="leader", fencing=12, ready=True)
        code, body = get(server.port, "/ready")
        assert code == 200
        assert body["fencing"] == 12
        assert get(server.port, "/nothing")[0] == 404
    finally:
        server.stop()


def test_a_single_control_without_postgresql_is_not_ready_before_its_loop_runs() -> None:
    control = StandbyControl(None, build_loop=lambda: None)  # type: ignore[arg-type,return-value]
    status = control.status()
    assert status["role"] == "leader"
    assert status["ready"] is False
    assert status["mqtt_connected"] is False


@pytest.fixture
def redis_client() -> Iterator[redis.Redis]:
    if not settings.REDIS_URL:
        pytest.skip("needs Redis")
    client = redis.Redis.from_url(settings.REDIS_URL)
    client.delete(LEADER_KEY)
    yield client
    client.delete(LEADER_KEY)


@pytest.mark.django_db
def test_web_ready_needs_a_recent_leader_heartbeat(redis_client: redis.Redis) -> None:
    response = Client().get("/ready")
    assert response.status_code == 503
    assert response.json()["database"] == "ok"
    assert response.json()["redis"] == "ok"
    assert "no control process" in response.json()["control"]

    beat = {"fencing": 3, "identity": "host:1", "at": time.time()}
    redis_client.set(LEADER_KEY, json.dumps(beat))
    response = Client().get("/ready")
    assert response.status_code == 200
    assert response.json()["ready"] is True

    redis_client.set(LEADER_KEY, json.dumps({**beat, "at": time.time() - health.HEARTBEAT_TTL - 1}))
    assert Client().get("/ready").status_code == 503  # a stale heartbeat is no leader


@pytest.mark.django_db
def test_web_ready_reports_a_broken_redis(settings: Any) -> None:
    settings.REDIS_URL = "redis://127.0.0.1:1/0"  # nothing listens on port 1
    response = Client().get("/ready")
    assert response.status_code == 503
    assert response.json()["redis"].startswith("failed")


def test_the_leader_heartbeat_is_written_only_while_ready(
    redis_client: redis.Redis, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setattr(health, "HEARTBEAT_EVERY", 0.05)
    status: dict[str, Any] = {"ready": False, "fencing": 5, "identity": "x:1"}
    beat = health.LeaderHeartbeat(lambda: status).start()
    try:
        time.sleep(0.3)
        assert health.read_leader_heartbeat() is None
        status["ready"] = True
        time.sleep(0.3)
        assert (health.read_leader_heartbeat() or {}).get("fencing") == 5
    finally:
        beat.stop()


@pytest.mark.e2e
@pytest.mark.timeout(400)
def test_the_celery_worker_check_answers_only_while_a_worker_runs(tmp_path: Path) -> None:
    """The worker's liveness check (docs/RELIABILITY_RESULTS.md): `celery inspect ping`."""
    if not settings.REDIS_URL:
        pytest.skip("needs Redis")
    env = {k: v for k, v in os.environ.items() if not k.startswith("PYTEST")}
    env.update({"REDIS_URL": settings.REDIS_URL, "DJANGO_SETTINGS_MODULE": "fleet.settings"})
    name = f"health-{uuid.uuid4().hex[:6]}@localhost"
    ping = [sys.executable, "-m", "celery", "-A", "fleet", "inspect", "ping"]
    ping += ["--destination", name, "--timeout", "2"]

    def check() -> int:
        return subprocess.run(ping, cwd=ROOT, env=env, capture_output=True, check=False).returncode  # noqa: S603

    assert check() != 0
    worker_argv = [sys.executable, "-m", "celery", "-A", "fleet", "worker", "--pool", "solo"]
    worker = Process("worker", [*worker_argv, "--hostname", name], env, tmp_path)
    try:
        wait_until(lambda: check() == 0, 240, "the worker answers the ping", [worker])
    finally:
        worker.terminate()
    assert check() != 0
