"""Duplicated, reordered and stale state messages (RELIABILITY.md §3 row 5): simulated vehicles
publish a share of their states twice with the same header id, hold some back behind the next
one, and stamp some with a timestamp minutes old; orders must finish as usual.

Figures: orders lost, duplicate-content publishes, control's duplicate/stale counters,
regressions (a vehicle's stored last node sequence id moving backwards within one order).
"""

import ast
import re
import signal
import threading
from typing import Any

from bench.faults.harness import Feeder, row_context, verdict, wait_all_closed, wait_online

VEHICLES = 3
MISBEHAVE = "duplicate_states=0.3,reorder_states=0.2,stale_states=0.2,stale_age=120,seed={seed}"


class RegressionWatch(threading.Thread):
    """Polls the vehicle rows; counts a (orderId, lastNodeSequenceId) pair going backwards."""

    def __init__(self) -> None:
        super().__init__(daemon=True)
        self.halt = threading.Event()
        self.regressions = 0
        self.samples = 0

    def run(self) -> None:
        from django.db import connection

        from robots.models import Vehicle

        last: dict[int, tuple[str, int | None]] = {}
        while not self.halt.wait(0.2):
            rows = Vehicle.objects.values_list("pk", "order_id", "last_node_sequence_id")
            for pk, order_id, sequence in rows:
                self.samples += 1
                before = last.get(pk)
                if (
                    before
                    and order_id
                    and before[0] == order_id
                    and sequence is not None
                    and before[1] is not None
                    and sequence < before[1]
                ):
                    self.regressions += 1
                last[pk] = (order_id, sequence)
        connection.close()


def run(*, full: bool, scale: float = 1.0) -> dict[str, Any]:
    with row_context(full=full) as context:
        fleet = context.fleet
        orders = context.pick(max(4, int(24 * scale)), 200)
        control = fleet.control()
        fleet.worker(beat=True)
        extra: list[str] = []
        for n in range(1, VEHICLES + 1):
            extra += ["--misbehave", f"AGV-{n}:" + MISBEHAVE.format(seed=n)]
        fleet.simulator("simulator", count=VEHICLES, extra=tuple(extra))
        wait_online(context, VEHICLES)
        watch = RegressionWatch()
        watch.start()
        feeder = Feeder(context, orders, in_flight=VEHICLES + 1)
        feeder.start()
        feeder.join(timeout=orders * 10)
        feeder.stop()
        drained = wait_all_closed(context, feeder.ids, timeout=300)
        watch.halt.set()
        watch.join(5)
        figures = verdict(context, feeder.ids)
        control.signal(signal.SIGTERM)
        assert control.popen is not None
        control.popen.wait(60)
        found = re.findall(r"control stopped; counters: (\{.*\})", control.output())
        counters = ast.literal_eval(found[-1]) if found else {}
        figures.update(
            {
                "misbehaviour": MISBEHAVE.format(seed="n"),
                "duplicates_dropped": counters.get("duplicate", 0),
                "stale_dropped": counters.get("stale", 0),
                "gaps": counters.get("gaps", 0),
                "handler_errors": counters.get("handler_errors", 0),
                "state_messages": counters.get("messages", 0),
                "regressions_observed": watch.regressions,
                "regression_samples": watch.samples,
                "drained_s": drained,
            }
        )
        figures["passed"] = bool(
            figures["nothing_lost"]
            and figures["all_finished"]
            and watch.regressions == 0
            and figures["handler_errors"] == 0
            and figures["duplicates_dropped"] > 0
        )
        return figures
