"""Celery worker killed mid-dispatch (RELIABILITY.md §3 row 3): `kill -9` of the prefork pool
child or of the whole worker, at a random moment 0–1.5 s after a new order was committed (the
dispatch task is received, running, committing or done), then the worker is started again.

acks_late + task_reject_on_worker_lost re-run a killed child's task; after a whole-worker kill
the task waits for Redis' visibility timeout, so beat's dispatch cycle (every 5 s, in its own
process here), a second worker (as deployed) and the database are what guarantee the order is
dispatched. Each kill waits until the killed worker is consuming again.

Figures: kills by kind, orders lost, duplicate-content publishes, orders on two vehicles, time
from an order's creation to its assignment p50/max (≤ lease 60 s).
"""

import os
import signal
import time
from functools import partial
from pathlib import Path
from typing import Any

from bench.faults.fleet import Process, percentile, python, wait_until
from bench.faults.harness import create_orders, row_context, verdict, wait_all_closed, wait_online

VEHICLES = 3


def _assignment_delays(ids: list[int]) -> list[float]:
    from orders.models import OrderEvent

    created: dict[int, Any] = {}
    delays = []
    for order_id, kind, at in OrderEvent.objects.filter(order_id__in=ids).values_list(
        "order_id", "kind", "at"
    ):
        if kind == OrderEvent.Kind.CREATED:
            created[order_id] = at
    for order_id, at in (
        OrderEvent.objects.filter(order_id__in=ids, kind=OrderEvent.Kind.ASSIGNED)
        .order_by("order_id", "at")
        .distinct("order_id")
        .values_list("order_id", "at")
    ):
        delays.append((at - created[order_id]).total_seconds())
    return delays


def _children(pid: int) -> list[int]:
    """The pool children of a worker (Linux /proc; no extra dependency)."""
    path = Path(f"/proc/{pid}/task/{pid}/children")
    return [int(child) for child in path.read_text().split()] if path.exists() else []


def _ready(worker: Process) -> bool:
    """The worker's log shows as many "ready." lines as it was started."""
    return worker.output().count(" ready.") >= worker.starts


def run(*, full: bool, scale: float = 1.0) -> dict[str, Any]:
    with row_context(full=full) as context:
        fleet = context.fleet
        kills = context.pick(max(2, int(10 * scale)), 50)
        fleet.control()
        worker = fleet.worker(pool="prefork")
        beat_argv = python("-m", "celery", "-A", "fleet", "beat", "-l", "INFO")
        fleet.add("beat", [*beat_argv, "--schedule", str(fleet.log_dir / "beat-schedule")])
        fleet.simulator("simulator", count=VEHICLES)
        wait_online(context, VEHICLES)
        ids: list[int] = []
        done: dict[str, int] = {"child": 0, "worker": 0}
        second = fleet.add(
            "worker2",
            python(
                "-m", "celery", "-A", "fleet", "worker", "-n", "w2@%h", "-P", "solo", "-l", "INFO"
            ),
        )
        beat = fleet.processes["beat"]
        # Everything consuming and beating first: start-up under load is not redispatch time.
        wait_until(partial(_ready, second), 300, "second worker ready", fleet)
        wait_until(lambda: "Sending due task" in beat.output(), 300, "beat running", fleet)
        boots: list[float] = []
        for n in range(kills):
            # Kill a worker that is consuming (a restart under load takes tens of seconds).
            boots.append(wait_until(partial(_ready, worker), 300, "worker ready", fleet))
            ids.extend(create_orders(context, 1))
            time.sleep(context.rng.uniform(0, 1.5))
            children = _children(worker.pid)
            if n % 2 == 0 and children:
                os.kill(children[0], signal.SIGKILL)
                done["child"] += 1
            else:
                worker.kill()
                worker.start()
                done["worker"] += 1
            time.sleep(context.rng.uniform(1, 4))
        drained = wait_all_closed(context, ids, timeout=300 + kills * 5)
        delays = _assignment_delays(ids)
        figures = verdict(context, ids)
        figures.update(
            {
                "kills": done,
                "second_worker": True,
                "worker_ready_wait_s_max": percentile(boots, 1.0),
                "assigned_s_p50": percentile(delays, 0.5),
                "assigned_s_max": percentile(delays, 1.0),
                "drained_s": drained,
            }
        )
        figures["passed"] = bool(
            figures["nothing_lost"]
            and figures["all_finished"]
            and (figures["assigned_s_max"] or 0) <= 60
        )
        return figures
