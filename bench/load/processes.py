"""The processes of the load benchmark: start, watch, measure and stop them (Django-free)."""

import contextlib
import os
import resource
import signal
import socket
import subprocess
import sys
import threading
import time
from pathlib import Path
from typing import IO, Any

import paho.mqtt.client as mqtt
import psutil
import psycopg
from paho.mqtt.enums import CallbackAPIVersion

ROOT = Path(__file__).resolve().parents[2]


def free_ports(count: int) -> list[int]:
    """`count` distinct free ports (all bound at once, so none is handed out twice)."""
    sockets = [socket.socket() for _ in range(count)]
    try:
        for sock in sockets:
            sock.bind(("127.0.0.1", 0))
        return [int(sock.getsockname()[1]) for sock in sockets]
    finally:
        for sock in sockets:
            sock.close()


class Child:
    """A started process, its log file and its psutil handle (children included for CPU)."""

    def __init__(self, name: str, argv: list[str], env: dict[str, str], logs: Path) -> None:
        self.name = name
        self.log: IO[bytes] = (logs / f"{name}.log").open("wb")
        self.popen = subprocess.Popen(
            argv,
            cwd=ROOT,
            env=env,
            stdout=self.log,
            stderr=subprocess.STDOUT,
            start_new_session=True,
            preexec_fn=_raise_file_limit,
        )
        self.process = psutil.Process(self.popen.pid)

    def tree(self) -> list[psutil.Process]:
        try:
            return [self.process, *self.process.children(recursive=True)]
        except psutil.NoSuchProcess:
            return []

    def cpu_seconds(self, *, kernel_only: bool = False) -> float:
        """CPU time of the process and its children (user + system, or system alone)."""
        total = 0.0
        for process in self.tree():
            try:
                times = process.cpu_times()
                total += times.system if kernel_only else times.user + times.system
            except psutil.NoSuchProcess:
                pass
        return total

    def rss_mb(self) -> float:
        total = 0
        for process in self.tree():
            with contextlib.suppress(psutil.NoSuchProcess):
                total += process.memory_info().rss
        return round(total / 2**20, 1)

    def stop(self, timeout: float = 20.0) -> int | None:
        if self.popen.poll() is None:
            with contextlib.suppress(ProcessLookupError):
                os.killpg(self.popen.pid, signal.SIGTERM)
        try:
            code = self.popen.wait(timeout=timeout)
        except subprocess.TimeoutExpired:
            os.killpg(self.popen.pid, signal.SIGKILL)
            code = self.popen.wait()
        self.log.close()
        return code


def _raise_file_limit() -> None:
    soft, hard = resource.getrlimit(resource.RLIMIT_NOFILE)
    wanted = 8192 if hard == resource.RLIM_INFINITY else min(8192, hard)
    if soft < wanted:
        resource.setrlimit(resource.RLIMIT_NOFILE, (wanted, hard))


def python(*args: str) -> list[str]:
    return [sys.executable, *args]


def create_database(admin_url: str, name: str) -> None:
    with psycopg.connect(admin_url, autocommit=True) as connection:
        connection.execute(f'DROP DATABASE IF EXISTS "{name}" WITH (FORCE)')
        connection.execute(f'CREATE DATABASE "{name}"')


class BrokerDrops:
    """Mosquitto's count of messages it dropped (queue limits) since it started, watched from
    before the window to its end on `$SYS/broker/publish/messages/dropped`.

    Mosquitto publishes that value retained but only when it changes, with a 60 s expiry: a
    client that subscribes at the end of a window without drops gets nothing (the tenth and
    eleventh rounds had `broker_dropped: null`). Subscribed from the start, the watcher has the
    retained value at once and every change after it."""

    TOPIC = "$SYS/broker/publish/messages/dropped"

    def __init__(self, port: int) -> None:
        self.value: int | None = None
        self._arrived = threading.Event()
        self._client = mqtt.Client(
            CallbackAPIVersion.VERSION2, client_id=f"loadbench-sys-{os.getpid()}"
        )
        self._client.on_message = self._on_message
        self._client.connect("127.0.0.1", port, 30)
        self._client.subscribe(self.TOPIC, 0)
        self._client.loop_start()

    def _on_message(self, _c: mqtt.Client, _u: Any, message: mqtt.MQTTMessage) -> None:
        with contextlib.suppress(ValueError):
            self.value = int(message.payload)
            self._arrived.set()

    def read(self, timeout: float = 15.0) -> int | None:
        """The latest count (None if Mosquitto has not said it within `timeout` of the start)."""
        self._arrived.wait(timeout)
        return self.value

    def close(self) -> None:
        self._client.disconnect()
        self._client.loop_stop()


def db_stats(url: str, name: str) -> dict[str, int]:
    with psycopg.connect(url, autocommit=True) as connection:
        row = connection.execute(
            "SELECT tup_inserted, tup_updated, tup_deleted, xact_commit "
            "FROM pg_stat_database WHERE datname = %s",
            (name,),
        ).fetchone()
        assert row is not None
        online = connection.execute(
            "SELECT count(*) FROM robots_vehicle WHERE connection = 'ONLINE'"
        ).fetchone()
    return {
        "inserted": row[0],
        "updated": row[1],
        "deleted": row[2],
        "commits": row[3],
        "online": online[0] if online else 0,
    }


def wait_for(condition: Any, timeout: float, what: str, children: list[Child]) -> None:
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        if condition():
            return
        for child in children:
            if child.popen.poll() is not None:
                raise SystemExit(f"{child.name} exited early; see its log")
        time.sleep(1.0)
    raise SystemExit(f"timed out after {timeout:.0f} s waiting for {what}")


def order_statuses(url: str, timeline: dict[str, list[float | None]]) -> dict[str, int]:
    """How many of the orders the API client posted are in each status at the end of the
    window (FINISHED, IN_PROGRESS, …): the "nothing lost" count of the run."""
    rows = _read_posted(
        url,
        timeline,
        "SELECT status, count(*) FROM orders_transportorder WHERE id = ANY(%s) "
        "GROUP BY status ORDER BY status",
    )
    return {str(status): int(count) for status, count in rows}


def _read_posted(url: str, timeline: dict[str, list[float | None]], sql: str) -> list[Any]:
    """Rows of `sql`, whose one parameter is the ids of the orders the API client posted."""
    ids = [int(order_id.removeprefix("TO-")) for order_id in timeline]
    with psycopg.connect(url, autocommit=True) as connection:
        return connection.execute(sql, (ids,)).fetchall()


def order_stages(url: str, timeline: dict[str, list[float | None]]) -> dict[str, Any]:
    """Where API → published goes, per order the API client posted: POST started → row created
    (the request), created → assigned (Celery and a dispatch cycle), assigned → first order
    message seen on MQTT (control's wake-up, plan and publish); p50/p95/max in ms."""
    from bench.load.probes import ms, percentile

    rows = _read_posted(
        url,
        timeline,
        "SELECT id, extract(epoch FROM created_at), extract(epoch FROM assigned_at) "
        "FROM orders_transportorder WHERE id = ANY(%s)",
    )
    stages: dict[str, list[float]] = {"request": [], "to_assigned": [], "to_published": []}
    for pk, created, assigned in rows:
        posted, published = timeline[f"TO-{pk}"]
        assert posted is not None
        stages["request"].append(float(created) - posted)
        if assigned is not None:
            stages["to_assigned"].append(float(assigned) - float(created))
            if published is not None:
                stages["to_published"].append(published - float(assigned))
    return {
        f"{name}_{label}_ms": ms(value)
        for name, samples in stages.items()
        for label, value in (
            ("p50", percentile(samples, 0.5)),
            ("p95", percentile(samples, 0.95)),
            ("max", max(samples) if samples else None),
        )
    }
