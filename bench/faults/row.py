"""Run one fault row in this process: `python -m bench.faults.row NAME [--full] [--out FILE]`.

Each row gets a fresh process because Django is set up once, on the row's own PostgreSQL.
"""

import argparse
import importlib
import json
import sys
import time
from pathlib import Path

from bench import results

ROWS = {
    "malformed": "bench.faults.rows.malformed",
    "broker": "bench.faults.rows.broker",
    "control": "bench.faults.rows.control_kill",
    "database": "bench.faults.rows.database",
    "worker": "bench.faults.rows.worker",
    "link": "bench.faults.rows.link",
    "redis": "bench.faults.rows.redis_loss",
    "idempotency": "bench.faults.rows.idempotency",
    "messages": "bench.faults.rows.messages",
    "clock": "bench.faults.rows.clock",
}


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("row", choices=sorted(ROWS))
    parser.add_argument("--full", action="store_true", help="the counts of RELIABILITY.md §5")
    parser.add_argument("--scale", type=float, default=1.0, help="shrink the quick counts (CI)")
    parser.add_argument("--out", type=Path, help="write the figures here, not bench/results")
    args = parser.parse_args(argv)
    module = importlib.import_module(ROWS[args.row])
    started = time.monotonic()
    figures = module.run(full=args.full, scale=args.scale)
    figures = {"row": args.row, "full": args.full, **figures}
    figures["seconds"] = round(time.monotonic() - started, 1)
    if args.out:
        args.out.write_text(json.dumps(figures, indent=2, sort_keys=True) + "\n")
    else:
        results.write(f"faults_{args.row}", figures)
    print(f"FIGURE {args.row}: {json.dumps(figures, sort_keys=True)}", flush=True)
    return 0 if figures.get("passed") else 1


if __name__ == "__main__":
    sys.exit(main())
