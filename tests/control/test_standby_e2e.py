"""Split brain, short (RELIABILITY.md §3 row 10): two `control` processes on a throw-away
PostgreSQL and Mosquitto; the leader is frozen, killed and its database restarted once each, with
vehicles driving orders. The broker's own log says who published: never two at once."""

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

from bench.faults.stack import PG_BIN

pytestmark = [pytest.mark.e2e, pytest.mark.timeout(400)]
ROOT = Path(__file__).resolve().parents[2]


def test_the_standby_takes_over_and_there_are_never_two_publishers(tmp_path: Path) -> None:
    if not (PG_BIN / "initdb").exists():
        pytest.skip(f"needs PostgreSQL server binaries in {PG_BIN}")
    out = tmp_path / "split_brain.json"
    env = {k: v for k, v in os.environ.items() if not k.startswith(("PYTEST", "TEST_"))}
    env.pop("DJANGO_SETTINGS_MODULE", None)
    argv = ["-m", "bench.faults.split_brain", "--rounds", "3", "--freeze", "8", "--vehicles", "2"]
    run = subprocess.run(  # noqa: S603 (our interpreter and module)
        [sys.executable, *argv, "--out", str(out)],
        cwd=ROOT,
        env=env,
        capture_output=True,
        text=True,
        timeout=380,
        check=False,
    )
    assert out.exists(), run.stdout[-3000:] + run.stderr[-3000:]
    figures = json.loads(out.read_text())
    assert figures["rounds_by_kind"] == {"kill": 1, "freeze": 1, "database": 1}
    assert figures["two_publisher_seconds"] == 0
    assert figures["stale_publishes"] == 0
    assert figures["publisher_terms"] >= 3  # the publishes really came from several terms
    assert figures["attribution_mismatches"] == 0
    assert figures["lost_orders"] == 0
    assert figures["duplicate_content_order_publishes"] == 0
    assert figures["failover_s_max"] <= 15.0
