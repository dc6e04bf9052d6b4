"""Smoke test of the load benchmark (`python -m bench.load --quick`): 50 vehicles for 15 s
against the real processes; every figure it reports must come out of the run."""

import json
import subprocess
import sys
import uuid
from pathlib import Path

import pytest
from django.conf import settings

pytestmark = [pytest.mark.e2e, pytest.mark.timeout(600)]

ROOT = Path(__file__).resolve().parents[2]


def test_quick_load_run_measures_every_figure(tmp_path: Path) -> None:
    chosen = getattr(settings, "SERVICES", {})  # tests.settings: the services this run uses
    services = {name: chosen.get(name, "") for name in ("DATABASE_URL", "REDIS_URL")}
    if not services["DATABASE_URL"].startswith("postgres") or not services["REDIS_URL"]:
        pytest.skip(f"needs PostgreSQL and Redis; have {services}")
    db = settings.DATABASES["default"]
    out = tmp_path / "load.json"
    database = f"{db['NAME']}_load_{uuid.uuid4().hex[:6]}"

    run = subprocess.run(
        [
            sys.executable, "-m", "bench.load", "--quick", "--json", str(out),
            "--postgres", f"postgres://{db['USER']}@{db['HOST']}:{db['PORT']}",
            "--database", database, "--redis", services["REDIS_URL"], "--order-rate", "0.5",
        ],
        cwd=ROOT,
        capture_output=True,
        text=True,
        timeout=540,
    )  # fmt: skip

    assert run.returncode == 0, run.stdout[-3000:] + run.stderr[-3000:]
    figures = json.loads(out.read_text())
    raw, control = figures["raw_subscriber"], figures["control"]
    assert raw["messages_per_s"] > 50  # 50 vehicles: 2 states + 1 visualization per second
    assert raw["by_topic_per_s"]["state"] > 0
    assert 0.8 < figures["receive_ratio_control_to_raw"] <= 1.05
    assert control["decode_errors"] == 0
    assert control["traffic_safety"] == {"cycles": 0, "stalled": 0}
    assert control["traffic_problems"] == 0
    assert figures["cpu_share"]["control"] > 0
    assert figures["control_cpu_vs_raw_subscriber"] is not None
    assert figures["memory_rss_mb"]["control"] > 0
    assert raw["caused_updates"] > 0  # control's cause log paired with the probe's arrivals
    assert raw["state_to_update_causal_p99_ms"] is not None
    assert figures["api"]["posted"] > 0
    assert figures["api"]["errors"] == 0
    assert figures["api"]["published"] > 0
    assert figures["api"]["post_to_published_p95_ms"] is not None
    # every posted order is somewhere: finished, under way or waiting, none failed
    statuses = figures["api"]["status_at_end"]
    assert sum(statuses.values()) == figures["api"]["posted"]
    assert not {"FAILED", "CANCELLED"} & statuses.keys()
    assert figures["browser"]["messages_per_s"] > 0
    assert figures["browser"]["closed_by_server"] == 0
    assert figures["db_rows_per_s"]["updated"] > 0
    assert figures["broker_dropped"] is not None  # Mosquitto's count, watched over the window
    assert "exit codes" in run.stdout
