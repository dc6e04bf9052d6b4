"""Coverage-guided fuzzing of control's inbound MQTT path (atheris; RELIABILITY.md §4, §5 Fuzz).

The target is `Controller.handle_message(topic, payload)`, the entry point paho's callback
calls for every message: topic parsing, the size check, decoding and the version adapters,
the identity and header-id checks and every topic's handler. An input's first three bytes pick
the topic (kind, protocol major version, vehicle), the rest is the payload; the seeds are
valid messages of every kind (2.0, 2.1 and 3.0 states, connection, factsheet,
visualization), the hostile set of the fault suite's malformed row, and states with unknown
fields. A crash is any exception out of `handle_message` and any exception a handler raised
(control catches those so that one robot cannot stop the fleet, and counts them as
`handler_errors`: for the fuzzer they are defects all the same).

    .venv/bin/python -m bench.fuzz [--seconds 3600] [--corpus DIR]   # -> bench/results/fuzz.json

The parent process writes the seeds, runs the fuzzer as a child (libFuzzer ends the process
it runs in) and reports runs, coverage, corpus size and crashes from the child's output.
"""

import argparse
import json
import logging
import os
import random
import re
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

from bench import results

KINDS = ("state", "connection", "factsheet", "visualization", "instantActions", "order", "x")
VERSIONS = ("v2", "v1", "v3", "v9", "")
SERIALS = ("AGV-1", "AGV-2", "AGV-3", "other")


def topic_of(data: bytes) -> tuple[str, bytes]:
    """The topic an input picks with its first three bytes, and its payload (the rest)."""
    head = data[:3].ljust(3, b"\0")
    kind = KINDS[head[0] % len(KINDS)]
    version = VERSIONS[head[1] % len(VERSIONS)]
    serial = SERIALS[head[2] % len(SERIALS)]
    return f"uagv/{version}/sim/{serial}/{kind}", data[3:]


def _input(kind: str, version: str, serial: str, payload: bytes) -> bytes:
    return bytes([KINDS.index(kind), VERSIONS.index(version), SERIALS.index(serial)]) + payload


def seeds() -> list[bytes]:
    """Valid messages of every kind in 2.0, 2.1 and 3.0 as the simulator sends them, states
    with unknown fields, and the fault suite's hostile states."""
    from bench.faults import hostile
    from simulator import wire
    from simulator.config import StartPose, VehicleConfig
    from simulator.vehicle import VirtualVehicle
    from vda5050 import codec
    from vda5050.enums import ConnectionState

    out: list[bytes] = []
    for serial, version in zip(SERIALS[:3], ("2.0.0", "2.1.0", "3.0.0"), strict=True):
        major = f"v{version[0]}"
        config = VehicleConfig(serial_number=serial, version=version)
        vehicle = VirtualVehicle(config, StartPose("demo", "a", 0.0, 0.0))
        messages: list[tuple[str, Any]] = [("state", m) for m in wire.states(vehicle)]
        messages += [("visualization", wire.visualization(vehicle))]
        messages += [("factsheet", wire.factsheet(vehicle))]
        messages += [("connection", wire.connection(vehicle, c)) for c in ConnectionState]
        out += [_input(kind, major, serial, codec.encode(m)) for kind, m in messages]
    out.append(_input("state", "v2", "AGV-1", hostile.with_unknown_fields("AGV-1", 9, "b")))
    rng = random.Random(1)
    for _, payload in hostile.generate("AGV-1", 300, rng, big=()):
        out.append(_input("state", "v2", "AGV-1", payload))
    return out


class _Recorder(logging.Handler):
    """Keeps the exception of the last `handler failed` log record (control's catch-all)."""

    def __init__(self) -> None:
        super().__init__(logging.ERROR)
        self.last: BaseException | None = None

    def emit(self, record: logging.LogRecord) -> None:
        if record.exc_info and record.exc_info[1] is not None:
            self.last = record.exc_info[1]


def _child(argv: list[str]) -> None:
    import atheris

    os.environ.setdefault("DJANGO_SETTINGS_MODULE", "fleet.settings")
    import django

    django.setup()  # control's modules import the map store's models; nothing touches the DB
    with atheris.instrument_imports():  # control and vda5050, and what they import first
        import control.controller
        import vda5050  # noqa: F401
    from bench.traffic_control import Store, layout_index
    from maps.demo import warehouse_layout

    recorder = _Recorder()
    for name in ("control", "vda5050"):  # quiet (thousands of rejections a second), but kept
        logger = logging.getLogger(name)
        logger.handlers, logger.propagate, logger.level = [recorder], False, logging.ERROR
    layout, _ = layout_index(warehouse_layout(columns=4, rows=3))
    controller = control.controller.Controller(
        store=Store(layout, list(SERIALS[:3])),
        interface_name="uagv",
        publish=lambda topic, payload, qos: None,
    )
    controller.load()

    def one_input(data: bytes) -> None:
        topic, payload = topic_of(data)
        before = controller.counters["handler_errors"]
        controller.handle_message(topic, payload)
        if controller.counters["handler_errors"] != before:
            failure = recorder.last
            raise RuntimeError(f"a handler raised on {topic}") from failure

    atheris.Setup(argv, one_input)
    atheris.Fuzz()


_DONE = re.compile(r"Done (\d+) runs in (\d+) second")
_STATUS = re.compile(r"#(\d+)\s+\w+\s+cov: (\d+) ft: (\d+) corp: (\d+)/")


def dictionary(inputs: list[bytes]) -> list[str]:
    """libFuzzer dictionary entries: every JSON key and string value of the seeds, quoted
    (mutations then insert `"nodeStates"` or `"FATAL"` whole instead of byte by byte)."""
    tokens: set[str] = set()

    def walk(value: Any) -> None:
        if isinstance(value, dict):
            for key, item in value.items():
                tokens.add(json.dumps(key))
                walk(item)
        elif isinstance(value, list):
            for item in value:
                walk(item)
        elif isinstance(value, str) and len(value) <= 40:
            tokens.add(json.dumps(value))

    for data in inputs:
        try:
            walk(json.loads(topic_of(data)[1]))
        except (ValueError, RecursionError):
            continue  # a hostile seed
    return [json.dumps(token) for token in sorted(tokens)]


def run(seconds: int, corpus: Path, workdir: Path) -> dict[str, Any]:
    """Seed `corpus`, fuzz for `seconds` in a child process, return the figures."""
    corpus.mkdir(parents=True, exist_ok=True)
    inputs = seeds()
    for index, seed in enumerate(inputs):
        (corpus / f"seed-{index:04d}").write_bytes(seed)
    tokens = workdir / "vda5050.dict"
    tokens.write_text("\n".join(dictionary(inputs)) + "\n")
    command = [sys.executable, "-m", "bench.fuzz", "--child", f"-max_total_time={seconds}"]
    command += ["-rss_limit_mb=4096", "-max_len=65536", "-timeout=10", "-print_final_stats=1"]
    command += [f"-dict={tokens}"]
    command += [f"-artifact_prefix={workdir}/", str(corpus)]
    started = time.monotonic()
    log = workdir / "fuzz.log"
    with log.open("w") as out:
        code = subprocess.call(command, stdout=out, stderr=subprocess.STDOUT)
    text = log.read_text(errors="replace")
    done = _DONE.search(text)
    statuses = _STATUS.findall(text)
    crashes = sorted(p.name for p in workdir.iterdir() if p.name.startswith(("crash-", "leak-")))
    return {
        "seconds": round(time.monotonic() - started, 1),
        "runs": int(done.group(1)) if done else (int(statuses[-1][0]) if statuses else 0),
        "coverage_edges": int(statuses[-1][1]) if statuses else None,
        "features": int(statuses[-1][2]) if statuses else None,
        "corpus": int(statuses[-1][3]) if statuses else None,
        "seeds": len(inputs),
        "exit_code": code,
        "crashes": crashes,
        "log": str(log),
    }


def main() -> None:
    if "--child" in sys.argv:
        _child([a for a in sys.argv if a != "--child"])
        return
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--seconds", type=int, default=3600)
    parser.add_argument("--corpus", type=Path, default=None, help="kept between runs if given")
    parser.add_argument("--out", default="fuzz", help="name of the JSON file under bench/results")
    parser.add_argument("--json", type=Path, help="write the figures here instead (tests)")
    args = parser.parse_args()
    workdir = Path(tempfile.mkdtemp(prefix="fleet-fuzz-"))
    figures = run(args.seconds, args.corpus or workdir / "corpus", workdir)
    print(json.dumps(figures, indent=2))
    if args.json:
        args.json.write_text(json.dumps(figures, indent=2))
    else:
        results.write(args.out, figures)
    if figures["crashes"] or figures["exit_code"] != 0:
        sys.exit(1)


if __name__ == "__main__":
    main()
