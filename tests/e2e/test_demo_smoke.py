"""Smoke test of `make demo` on embedded defaults: it starts, serves `/`, a vehicle moves, it
stops cleanly on SIGTERM."""

import base64
import json
import os
import time
import urllib.error
import urllib.request
from pathlib import Path

import pytest

from tests.e2e.processes import Process, free_port, wait_until

pytestmark = pytest.mark.e2e


def get(url: str, auth: bool = False) -> tuple[int, bytes]:
    request = urllib.request.Request(url)
    if auth:
        request.add_header("Authorization", "Basic " + base64.b64encode(b"admin:admin").decode())
    try:
        with urllib.request.urlopen(request, timeout=5) as response:  # noqa: S310 (localhost)
            return response.status, response.read()
    except urllib.error.HTTPError as error:
        return error.code, error.read()
    except OSError:
        return 0, b""


def positions(base: str) -> dict[str, tuple[float, float]]:
    status, body = get(f"{base}/api/v1/vehicles/", auth=True)
    if status != 200:
        return {}
    return {
        v["serial_number"]: (v["x"], v["y"])
        for v in json.loads(body)["results"]
        if v["x"] is not None
    }


def test_make_demo_serves_moving_vehicles_and_stops_cleanly(tmp_path: Path) -> None:
    port = free_port()
    env = {
        key: value
        for key, value in os.environ.items()
        if key not in {"DATABASE_URL", "REDIS_URL", "MQTT_URL", "DJANGO_SETTINGS_MODULE"}
        and not key.startswith("PYTEST")
    }
    env |= {
        "DATABASE_URL": f"sqlite:///{tmp_path}/demo.sqlite3",
        "MQTT_EMBEDDED_PORT": str(free_port()),
        "VDA5050_INTERFACE": "uagv",
    }
    started = time.monotonic()
    demo = Process(
        "demo",
        [
            "make",
            "--no-print-directory",
            "demo",
            f"DEMO_ARGS=--port {port} --vehicles 2 --time-scale 5",
        ],
        env,
        tmp_path,
        new_session=True,
    )
    base = f"http://127.0.0.1:{port}"
    try:
        wait_until(lambda: get(f"{base}/health")[0] == 200, 120, "demo serves /health", [demo])
        startup = time.monotonic() - started
        status, _ = get(f"{base}/")
        assert status in (200, 302)  # the live page asks for a login
        first = wait_until(lambda: positions(base), 60, "vehicles report positions", [demo])
        wait_until(
            lambda: any(positions(base).get(k) != v for k, v in first.items()),
            60,
            "a vehicle moves",
            [demo],
        )
    finally:
        code = demo.terminate(timeout=30)
    output = demo.output()
    assert "Open Fleet demo: http://127.0.0.1" in output
    assert "demo stopped" in output, output[-3000:]
    assert get(f"{base}/health")[0] == 0  # nothing listens any more
    print(f"demo smoke: ready in {startup:.1f} s, exit code {code}")
