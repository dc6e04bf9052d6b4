"""The fault suite: `python -m bench.faults [row ...] [--full]` (`make bench-faults`).

Each row runs in its own process with its own Mosquitto, Redis and PostgreSQL, prints its
figure and writes bench/results/faults_<row>.json. Without rows: all of them, then the standby
helper's split-brain row (bench/faults/split_brain.py) when it is present.
"""

import argparse
import importlib.util
import json
import subprocess
import sys
import time

from bench.faults.row import ROWS
from bench.results import RESULTS


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("rows", nargs="*", help=f"some of: {', '.join(ROWS)} (default all)")
    parser.add_argument("--full", action="store_true", help="the counts of RELIABILITY.md §5")
    args = parser.parse_args()
    unknown = set(args.rows) - set(ROWS) - {"split_brain"}
    if unknown:
        parser.error(f"unknown rows: {', '.join(sorted(unknown))}")
    rows = args.rows or list(ROWS)
    if not args.rows and importlib.util.find_spec("bench.faults.split_brain") is not None:
        rows.append("split_brain")
    summary: dict[str, object] = {}
    for row in rows:
        started, wall_start = time.monotonic(), time.time()
        if row == "split_brain":  # the standby helper's row: 20 rounds is its §5 count
            rounds = "20" if args.full else "3"
            argv = [sys.executable, "-m", "bench.faults.split_brain", "--rounds", rounds]
        else:
            argv = [sys.executable, "-m", "bench.faults.row", row]
            argv += ["--full"] if args.full else []
        code = subprocess.call(argv)
        result = RESULTS / f"faults_{row}.json"
        passed = None
        if result.exists() and result.stat().st_mtime >= wall_start:  # not an earlier run's
            passed = json.loads(result.read_text()).get("passed")
        summary[row] = {"exit": code, "passed": passed, "s": round(time.monotonic() - started)}
        print(f"== {row}: exit {code}, passed {passed}", flush=True)
    print(json.dumps(summary, indent=2))
    return 0 if all(v["exit"] == 0 for v in summary.values()) else 1  # type: ignore[index]


if __name__ == "__main__":
    sys.exit(main())
