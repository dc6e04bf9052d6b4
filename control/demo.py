"""Pieces of `manage.py run_demo`: child processes, the demo data and a stream of orders."""

import logging
import os
import random
import signal
import socket
import subprocess
import sys
import threading
import time
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from django.contrib.auth import get_user_model
from django.db import close_old_connections

from fleet import roles
from maps.demo import warehouse_layout
from maps.models import Map, Station
from maps.services import create_layout
from orders.models import TransportOrder
from orders.services import create_transport_order

logger = logging.getLogger(__name__)

DEMO_USER, DEMO_PASSWORD = "admin", "admin"  # noqa: S105 (printed for the demo's local login)
# One login per role to try the permissions (user name = password = role; local demo only).
DEMO_ROLE_USERS = (roles.OPERATOR, roles.TECHNICIAN, roles.MANAGER)


def ensure_demo_data() -> Map:
    """The demo layout, a superuser to log in with and one user per role, created once."""
    layout = Map.objects.filter(map_id="demo").first() or create_layout(spec=warehouse_layout())
    users = get_user_model().objects
    if not users.filter(username=DEMO_USER).exists():
        users.create_superuser(DEMO_USER, "admin@example.invalid", DEMO_PASSWORD)
    for role in DEMO_ROLE_USERS:
        if not users.filter(username=role).exists():
            roles.assign_role(user=users.create_user(role, password=role), role=role)
    return layout


def wait_for_port(host: str, port: int, timeout: float = 20.0) -> None:
    """Block until something listens on host:port (a child process finished starting)."""
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        try:
            with socket.create_connection((host, port), timeout=0.5):
                return
        except OSError:
            time.sleep(0.1)
    raise RuntimeError(f"nothing listens on {host}:{port} after {timeout:.0f} s")


class Children:
    """Child processes started by the demo, stopped in reverse order with SIGTERM."""

    def __init__(self) -> None:
        self.processes: list[tuple[str, subprocess.Popen[bytes]]] = []

    def start(self, name: str, argv: Sequence[str], env: dict[str, str] | None = None) -> None:
        process = subprocess.Popen(  # noqa: S603 (our own interpreter and modules)
            list(argv),
            env={**os.environ, **(env or {})},
            cwd=Path(__file__).resolve().parent.parent,
        )
        self.processes.append((name, process))
        logger.info("started %s (pid %d)", name, process.pid)

    def python(self, name: str, *args: str) -> None:
        self.start(name, [sys.executable, *args])

    def failed(self) -> str | None:
        """The name of a child that exited on its own, if any."""
        return next((name for name, p in self.processes if p.poll() is not None), None)

    def stop(self) -> None:
        """Newest first, each waited for: the vehicles say OFFLINE before the broker goes."""
        for name, process in reversed(self.processes):
            if process.poll() is None:
                process.send_signal(signal.SIGTERM)
            try:
                process.wait(timeout=10)
            except subprocess.TimeoutExpired:
                logger.warning("%s did not stop in 10 s; killing it", name)
                process.kill()
                process.wait()


class OrderStream(threading.Thread):
    """Keeps about one open transport order per vehicle, from random pick to drop stations."""

    def __init__(self, layout: Map, vehicles: int, interval: float = 1.0) -> None:
        super().__init__(name="demo-orders", daemon=True)
        self.layout, self.vehicles, self.interval = layout, vehicles, interval
        self.stopped = threading.Event()
        self.random = random.Random(5050)  # noqa: S311 (demo data, not security)

    def run(self) -> None:
        while not self.stopped.wait(self.interval):
            try:
                self._top_up()
            except Exception:
                logger.exception("demo order stream failed; trying again")
            finally:
                close_old_connections()

    def _top_up(self) -> None:
        open_orders = TransportOrder.objects.filter(
            status__in=TransportOrder.OPEN_STATUSES, source__map=self.layout
        ).count()
        if open_orders >= self.vehicles + 1:
            return
        picks = list(Station.objects.filter(map=self.layout, kind=Station.Kind.PICK))
        drops = list(Station.objects.filter(map=self.layout, kind=Station.Kind.DROP))
        if picks and drops:
            create_transport_order(
                source=self.random.choice(picks),
                destination=self.random.choice(drops),
                load_id=f"L{self.random.randrange(10**6):06d}",
            )


class EmbeddedBeat(threading.Thread):
    """Celery beat for the embedded demo: runs CELERY_BEAT_SCHEDULE's tasks in this process.

    Without Redis there is no broker for beat to send to, so the periodic work (dispatch cycle,
    charging, service plans, alert escalation, report roll-ups) runs here, each task at its own
    interval, eagerly, one after the other.
    """

    def __init__(self, schedule: dict[str, dict[str, Any]]) -> None:
        super().__init__(name="demo-beat", daemon=True)
        self.entries = [(entry["task"], float(entry["schedule"])) for entry in schedule.values()]
        self.stopped = threading.Event()

    def run(self) -> None:
        from celery import current_app

        due = {task: time.monotonic() + interval for task, interval in self.entries}
        while not self.stopped.wait(1.0):
            for task, interval in self.entries:
                if time.monotonic() < due[task]:
                    continue
                due[task] = time.monotonic() + interval
                try:
                    current_app.tasks[task].apply()
                except Exception:
                    logger.exception("periodic task %s failed; it runs again next time", task)
                finally:
                    close_old_connections()
