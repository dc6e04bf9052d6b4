"""The fault rows of bench/faults in short versions: each row runs as its own process with its
own Mosquitto, Redis and PostgreSQL (so nothing here touches the shared services)."""

import json
import shutil
import subprocess
import sys
from collections.abc import Callable
from pathlib import Path
from typing import Any

import pytest

from bench.faults.stack import PG_BIN, ROOT

NEEDED = ["mosquitto", "redis-server"]


@pytest.fixture
def run_row(tmp_path: Path) -> Callable[..., dict[str, Any]]:
    missing = [name for name in NEEDED if shutil.which(name) is None]
    if missing or not (PG_BIN / "initdb").exists():
        pytest.skip(f"needs Mosquitto, Redis and PostgreSQL 15 binaries (missing {missing})")

    def run(row: str, scale: float, timeout: float = 240) -> dict[str, Any]:
        out = tmp_path / f"{row}.json"
        argv = [sys.executable, "-m", "bench.faults.row", row, "--scale", str(scale)]
        done = subprocess.run(
            [*argv, "--out", str(out)],
            cwd=ROOT,
            capture_output=True,
            text=True,
            timeout=timeout,
            env={k: v for k, v in __import__("os").environ.items() if not k.startswith("PYTEST")},
        )
        if not out.exists():
            pytest.fail(
                f"row {row} wrote no figures:\n{done.stdout[-3000:]}\n{done.stderr[-5000:]}"
            )
        figures: dict[str, Any] = json.loads(out.read_text())
        print(f"{row}: {json.dumps(figures, sort_keys=True)}")
        return figures

    return run
