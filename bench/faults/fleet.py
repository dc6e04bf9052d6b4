"""The fleet's processes for a fault row (control, Celery worker and beat, web, simulators) and
the independent MQTT observer that counts what the master publishes.

Django must be set up (with the row's own DATABASE_URL) before the helpers that touch the
database are called; the processes only need the environment.
"""

import hashlib
import json
import os
import signal
import subprocess
import sys
import tempfile
import threading
import time
import uuid
from collections import defaultdict
from collections.abc import Callable
from pathlib import Path
from typing import IO, Any

import paho.mqtt.client as mqtt
from paho.mqtt.enums import CallbackAPIVersion

from bench.faults.stack import ROOT, Stack, free_port, port_open

HEADER_FIELDS = ("headerId", "timestamp")


class Process:
    """A child process whose output goes to a log file; signalled by its pid only."""

    def __init__(self, name: str, argv: list[str], env: dict[str, str], log_dir: Path) -> None:
        self.name, self.argv, self.env = name, argv, env
        self.log_path = log_dir / f"{name}.log"
        self._log: IO[bytes] | None = None
        self.popen: subprocess.Popen[bytes] | None = None
        self.starts = 0
        self.start()

    def start(self) -> None:
        self._log = self.log_path.open("ab")
        # A session of its own: when the shell that started the row exits while a vehicle is
        # SIGSTOPped, the kernel sends the orphaned process group SIGHUP + SIGCONT, which woke the
        # frozen vehicle and restarted Celery mid-row. Every signal here goes to the pid anyway.
        self.popen = subprocess.Popen(
            self.argv,
            cwd=ROOT,
            env=self.env,
            stdout=self._log,
            stderr=subprocess.STDOUT,
            start_new_session=True,
        )
        self.starts += 1

    @property
    def pid(self) -> int:
        assert self.popen is not None
        return self.popen.pid

    def alive(self) -> bool:
        return self.popen is not None and self.popen.poll() is None

    def signal(self, sig: int) -> None:
        assert self.popen is not None
        os.kill(self.popen.pid, sig)

    def kill(self) -> None:
        """SIGKILL and reap."""
        if self.alive():
            self.signal(signal.SIGKILL)
        assert self.popen is not None
        self.popen.wait(timeout=30)

    def terminate(self, timeout: float = 20.0) -> int | None:
        if self.popen is None:
            return None
        if self.popen.poll() is None:
            try:
                self.popen.send_signal(signal.SIGCONT)
                self.popen.send_signal(signal.SIGTERM)
                code = self.popen.wait(timeout=timeout)
            except subprocess.TimeoutExpired:
                self.popen.kill()
                code = self.popen.wait()
        else:
            code = self.popen.returncode
        if self._log is not None:
            self._log.close()
        return code

    def output(self) -> str:
        if self._log is not None and not self._log.closed:
            self._log.flush()
        return self.log_path.read_text(errors="replace")


def python(*args: str) -> list[str]:
    return [sys.executable, *args]


class Fleet:
    """The processes of one row on one Stack. Every start/stop is by pid."""

    def __init__(self, stack: Stack, *, time_scale: float = 10.0) -> None:
        self.stack = stack
        # Logs outlive the row's services: read them after a failure.
        self.log_dir = Path(tempfile.mkdtemp(prefix="fleet-faults-logs-"))
        self.interface = f"faults{uuid.uuid4().hex[:6]}"
        self.time_scale = time_scale
        self.env = {k: v for k, v in os.environ.items() if not k.startswith("PYTEST")}
        self.env.update(stack.env())
        self.env.update(
            {
                "DJANGO_SETTINGS_MODULE": "fleet.settings",
                "VDA5050_INTERFACE": self.interface,
                "CELERY_TASK_ALWAYS_EAGER": "0",
                "FLEET_FLUSH_INTERVAL": "0.5",
                # Orders released FLEET_BASE_AHEAD nodes at a time (still order updates), without
                # traffic planning: an idle vehicle holding a drop station would otherwise stall
                # the stream (a known gap) and the rows measure faults, not traffic.
                "FLEET_TRAFFIC": os.environ.get("FAULTS_TRAFFIC", "0"),
                "PYTHONUNBUFFERED": "1",
            }
        )
        self.processes: dict[str, Process] = {}
        self.layout_file = self.log_dir / "layout.json"
        self.web_port = 0

    def add(self, name: str, argv: list[str], env: dict[str, str] | None = None) -> Process:
        process = Process(name, argv, env or self.env, self.log_dir)
        self.processes[name] = process
        return process

    def control(self) -> Process:
        return self.add("control", python("manage.py", "run_control"))

    def worker(self, *, pool: str = "solo", beat: bool = False) -> Process:
        argv = python("-m", "celery", "-A", "fleet", "worker", "--pool", pool, "-l", "INFO")
        if pool == "prefork":
            argv += ["--concurrency", "1"]
        if beat:
            argv += ["--beat", "--schedule", str(self.log_dir / "beat-schedule")]
        return self.add("worker", argv)

    def web(self) -> Process:
        self.web_port = free_port()
        argv = python("-m", "daphne", "-b", "127.0.0.1", "-p", str(self.web_port))
        process = self.add("web", [*argv, "fleet.asgi:application"])
        wait_until(lambda: port_open(self.web_port), 240, "web serving", self)
        return process

    def simulator(
        self, name: str, *, count: int, prefix: str = "AGV-", extra: tuple[str, ...] = ()
    ) -> Process:
        argv = python("-m", "simulator", "--count", str(count), "--layout", str(self.layout_file))
        argv += ["--broker", self.stack.mosquitto.url, "--interface", self.interface]
        argv += ["--time-scale", str(self.time_scale), "--serial-prefix", prefix, *extra]
        return self.add(name, argv)

    def write_layout(self, layout: Any) -> None:
        from maps.selectors import layout_as_dict

        self.layout_file.write_text(json.dumps(layout_as_dict(map=layout)))

    def close(self) -> dict[str, int | None]:
        return {name: p.terminate() for name, p in self.processes.items()}

    def check_alive(self) -> None:
        for process in self.processes.values():
            if not process.alive():
                tail = process.output()[-3000:]
                raise RuntimeError(f"{process.name} exited unexpectedly:\n{tail}")


def _digest(document: dict[str, Any]) -> str:
    content = {k: v for k, v in document.items() if k not in HEADER_FIELDS}
    return hashlib.sha256(json.dumps(content, sort_keys=True).encode()).hexdigest()


class Observer:
    """An MQTT client of its own that records every order and instant action the master
    publishes, and when each vehicle's state was last seen.

    Duplicate-content publish: the same (vehicle, orderId, orderUpdateId) — or the same
    instant action id — published with two different contents (header id and timestamp aside).
    """

    def __init__(self, url: str, interface: str) -> None:
        self.interface = interface
        self.lock = threading.Lock()
        self.orders: dict[tuple[str, str, int], set[str]] = defaultdict(set)
        self.order_publishes = 0
        self.order_vehicles: dict[str, set[str]] = defaultdict(set)
        self.actions: dict[str, set[str]] = defaultdict(set)
        self.action_publishes = 0
        self.action_types: dict[str, int] = defaultdict(int)
        self.state_seen: dict[str, float] = {}
        self.connection: dict[str, tuple[str, float]] = {}
        host, port = url.removeprefix("mqtt://").split(":")
        self.client = mqtt.Client(
            callback_api_version=CallbackAPIVersion.VERSION2,
            client_id=f"observer-{uuid.uuid4().hex[:8]}",
            clean_session=False,
        )
        self.client.reconnect_delay_set(min_delay=1, max_delay=1)
        self.client.on_connect = self._on_connect
        self.client.on_message = self._on_message
        self.client.connect(host, int(port), keepalive=10)
        self.client.loop_start()

    def _on_connect(self, client: mqtt.Client, *args: Any) -> None:
        topics = ("order", "instantActions", "state", "connection")
        client.subscribe([(f"{self.interface}/+/+/+/{topic}", 1) for topic in topics])

    def _on_message(self, client: mqtt.Client, userdata: Any, msg: mqtt.MQTTMessage) -> None:
        parts = msg.topic.split("/")
        serial, kind = parts[3], parts[4]
        now = time.monotonic()
        try:  # the master's own messages only, but a stranger may publish anything here
            document = json.loads(msg.payload) if len(msg.payload) < 1_000_000 else None
        except Exception:  # noqa: BLE001 - RecursionError too (RELIABILITY §0.1)
            return
        if not isinstance(document, dict):
            return
        with self.lock:
            if kind == "order":
                self.order_publishes += 1
                key = (serial, document["orderId"], int(document["orderUpdateId"]))
                self.orders[key].add(_digest(document))
                self.order_vehicles[document["orderId"]].add(serial)
            elif kind == "instantActions":
                actions = document.get("actions") or document.get("instantActions") or []
                for action in actions:
                    self.action_publishes += 1
                    self.action_types[action.get("actionType", "?")] += 1
                    self.actions[f"{serial}/{action['actionId']}"].add(
                        hashlib.sha256(json.dumps(action, sort_keys=True).encode()).hexdigest()
                    )
            elif kind == "state":
                self.state_seen[serial] = now
            elif kind == "connection":
                self.connection[serial] = (str(document.get("connectionState")), now)

    def figures(self) -> dict[str, int]:
        with self.lock:
            return {
                "order_publishes": self.order_publishes,
                "order_messages_distinct": len(self.orders),
                "duplicate_content_order_publishes": sum(len(v) - 1 for v in self.orders.values()),
                "orders_sent_to_two_vehicles": sum(
                    1 for v in self.order_vehicles.values() if len(v) > 1
                ),
                "instant_action_publishes": self.action_publishes,
                "duplicate_content_instant_actions": sum(len(v) - 1 for v in self.actions.values()),
            }

    def stop(self) -> None:
        self.client.loop_stop()
        self.client.disconnect()


def wait_until(
    condition: Callable[[], object], timeout: float, message: str, fleet: Fleet | None = None
) -> float:
    """Seconds until `condition()` is truthy; TimeoutError naming `message` otherwise."""
    started = time.monotonic()
    while time.monotonic() - started < timeout:
        if condition():
            return time.monotonic() - started
        if fleet is not None:
            fleet.check_alive()
        time.sleep(0.2)
    raise TimeoutError(f"timed out after {timeout:.0f} s: {message}")


def percentile(values: list[float], share: float) -> float | None:
    if not values:
        return None
    ordered = sorted(values)
    index = min(len(ordered) - 1, max(0, round(share * (len(ordered) - 1))))
    return round(ordered[index], 3)
