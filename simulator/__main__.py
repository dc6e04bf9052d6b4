"""Command line: ``python -m simulator --count N --layout FILE [options]``.

Runs until SIGTERM/SIGINT, then every vehicle publishes OFFLINE and disconnects; exit 0.
``--version 3.0.0`` makes the vehicles speak 3.0 on ``interfaceName/v3/...``.
``--misbehave SERIAL:key=value,...`` (repeatable) and ``--script FILE.json`` make single
vehicles misbehave for conformance tests (keys: :data:`simulator.misbehaviour.KEYS`).
"""

from __future__ import annotations

import argparse
import json
import logging
import signal
import sys
import threading
from collections.abc import Sequence
from pathlib import Path
from types import FrameType
from typing import Any
from urllib.parse import unquote, urlsplit

from simulator.delays import DelayConfig, parse_range
from simulator.fleet import FleetConfig, SimulatedFleet
from simulator.layout import LayoutError, load_layout
from simulator.misbehaviour import KEYS, build_plan
from vda5050 import VDA5050Error

log = logging.getLogger("simulator")

_DEFAULT_PORT = 1883


def config_from_args(
    args: argparse.Namespace, broker: tuple[str, int, str | None, str | None], **extra: Any
) -> FleetConfig:
    """The fleet configuration the command-line options describe (shared with simulator.pump)."""
    host, port, user, password = broker
    return FleetConfig(
        count=args.count,
        broker_host=host,
        broker_port=port,
        username=user,
        password=password,
        interface=args.interface,
        manufacturer=args.manufacturer,
        version=args.version,
        speed=args.speed,
        time_scale=args.time_scale,
        visualization_hz=args.visualization_hz,
        state_interval=args.state_interval,
        serial_prefix=args.serial_prefix,
        tick_hz=args.tick_hz,
        **extra,
    )


def parse_broker(url: str) -> tuple[str, int, str | None, str | None]:
    """``mqtt://[user[:password]@]host[:port]`` → (host, port, user, password)."""
    parts = urlsplit(url if "://" in url else f"mqtt://{url}")
    if parts.scheme not in ("mqtt", "tcp"):
        raise ValueError(f"unsupported broker scheme {parts.scheme!r} (use mqtt://)")
    if not parts.hostname:
        raise ValueError(f"broker URL {url!r} has no host")
    user = unquote(parts.username) if parts.username else None
    password = unquote(parts.password) if parts.password else None
    return parts.hostname, parts.port or _DEFAULT_PORT, user, password


def _positive(text: str) -> float:
    value = float(text.split()[0])  # accept "1.5" as well as "1.5 m/s"
    if value <= 0:
        raise argparse.ArgumentTypeError(f"must be > 0, got {text}")
    return value


def _non_negative(text: str) -> float:
    value = float(text)
    if value < 0:
        raise argparse.ArgumentTypeError(f"must be >= 0, got {text}")
    return value


def build_parser() -> argparse.ArgumentParser:
    """The CLI definition (kept separate so tests and docs can introspect it)."""
    parser = argparse.ArgumentParser(
        prog="python -m simulator",
        description="Run N virtual VDA 5050 vehicles over MQTT.",
        epilog=(
            "misbehaviour keys (times in simulated seconds from start; lists joined by '+'): "
            + ", ".join(KEYS)
            + ". Example: --misbehave 'AGV-2:reject_orders=orderError,reject_count=1'"
        ),
    )
    add = parser.add_argument
    add("--count", type=int, required=True, help="number of vehicles")
    add("--layout", required=True, help="layout JSON exported by the fleet manager")
    add("--broker", default="mqtt://127.0.0.1:1883", help="mqtt://[user:pass@]host[:port]")
    add("--interface", default="uagv", help="interfaceName topic level")
    add("--manufacturer", default="sim", help="manufacturer topic level / header field")
    add(
        "--version",
        default="2.0.0",
        choices=["2.0.0", "2.1.0", "3.0.0"],
        help="VDA 5050 version (3.0.0 publishes on interfaceName/v3/...)",
    )
    add("--speed", type=_positive, default=1.0, help="driving speed in m/s")
    add("--time-scale", type=_positive, default=1.0, help="time-lapse factor (10 = 10x faster)")
    add("--visualization-hz", type=_non_negative, default=1.0, help="0 disables visualization")
    add("--state-interval", type=_positive, default=30.0, help="max seconds between states")
    add("--serial-prefix", default="AGV-", help="serial numbers are PREFIX1..PREFIXN")
    add("--tick-hz", type=_positive, default=10.0, help="simulation loop rate")
    add("--log-level", default="INFO", help="DEBUG, INFO, WARNING, ...")
    add(
        "--misbehave",
        action="append",
        default=[],
        metavar="SERIAL:KEY=VALUE[,KEY=VALUE...]",
        help="make one vehicle misbehave (repeatable), e.g. 'AGV-2:drop_orders=1'",
    )
    add(
        "--delay-share",
        type=float,
        default=0.0,
        help="share of moves started late (0..1), e.g. 0.05; see --delay-range",
    )
    add("--delay-range", default="5,30", help="LOW,HIGH simulated seconds of an injected delay")
    add("--delay-seed", type=int, default=1, help="random seed of the delay injection")
    add(
        "--summary",
        metavar="FILE.json",
        help="on exit write collisions (footprint overlaps) and injected delays to FILE",
    )
    add(
        "--script",
        metavar="FILE.json",
        help='misbehaviour script: [{"serial": "AGV-2", "reject_orders": "orderError"}, ...]',
    )
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point; returns the process exit code."""
    parser = build_parser()
    args = parser.parse_args(argv)
    logging.basicConfig(
        level=args.log_level.upper(),
        format="%(asctime)s %(levelname)s %(name)s: %(message)s",
    )
    if args.count < 1:
        parser.error("--count must be at least 1")
    try:
        host, port, user, password = parse_broker(args.broker)
        layout = load_layout(args.layout)
        misbehaviours = build_plan(args.misbehave, args.script)
        low, high = parse_range(args.delay_range)
        delays = DelayConfig(share=args.delay_share, low=low, high=high, seed=args.delay_seed)
    except (ValueError, LayoutError) as exc:
        parser.error(str(exc))
    config = config_from_args(
        args, (host, port, user, password), misbehaviours=misbehaviours, delays=delays
    )
    try:
        fleet = SimulatedFleet(layout, config)
    except (ValueError, VDA5050Error) as exc:  # e.g. a serial prefix topics forbid
        parser.error(str(exc))

    stop = threading.Event()

    def request_stop(signum: int, _frame: FrameType | None) -> None:
        log.info("received %s, stopping", signal.Signals(signum).name)
        stop.set()

    signal.signal(signal.SIGTERM, request_stop)
    signal.signal(signal.SIGINT, request_stop)
    fleet.start()
    log.info(
        "%d vehicles on %s:%d interface %r map %r (version %s, time scale %g)",
        config.count,
        host,
        port,
        config.interface,
        layout.map_id,
        config.version,
        config.time_scale,
    )
    # Wait in short slices so the signal handler gets to run promptly on every platform.
    while not stop.wait(0.5):
        pass
    fleet.stop()
    summary = fleet.summary()
    log.info("summary: %s", json.dumps(summary))
    if args.summary:
        Path(args.summary).write_text(json.dumps(summary, indent=2))
    return 0


if __name__ == "__main__":
    sys.exit(main())
