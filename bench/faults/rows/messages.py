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
    """Polls the vehicle rows; counts a (orderId, lastNodeSequenceId) pair going backwards.

    Only sequence ids of the order count: control numbers node i of an order's route 2·i, so
    a row's id belongs to its order when the route's node there is the row's lastNodeId. A
    vehicle that took a new order reports the previous order's lastNodeSequenceId (and node)
    with the new orderId until it passes the new first node: such rows are counted
    (`previous_order_sequence_samples`), not compared, until the order has made progress;
    after that they count as regressions too. Routes stay fixed: no traffic planning here.
    """

    def __init__(self) -> None:
        super().__init__(daemon=True)
        self.halt = threading.Event()
        self.regressions = 0
        self.leftovers = 0
        self.samples = 0
        self.examples: list[dict[str, Any]] = []
        self._routes: dict[str, list[str]] = {}

    def run(self) -> None:
        from django.db import connection

        from robots.models import Vehicle

        highest: dict[int, tuple[str, int]] = {}  # per vehicle: its order, highest id of it
        while not self.halt.wait(0.2):
            rows = Vehicle.objects.values_list(
                "pk", "order_id", "last_node_sequence_id", "last_node_id"
            )
            for pk, order_id, sequence, node in rows:
                self.samples += 1
                if not order_id or sequence is None:
                    continue
                before = highest.get(pk)
                if before is not None and before[0] != order_id:
                    before = None
                verdict = judge(before, sequence, of_order=self._of_order(order_id, sequence, node))
                if verdict == "progress":
                    highest[pk] = (order_id, sequence)
                elif verdict == "leftover":
                    self.leftovers += 1
                elif verdict == "regression" and before is not None:
                    self.regressions += 1
                    if len(self.examples) < 5:
                        self.examples.append(
                            {
                                "vehicle": pk,
                                "order": order_id,
                                "before": before[1],
                                "after": sequence,
                            }
                        )
        connection.close()

    def _of_order(self, order_id: str, sequence: int, node: str) -> bool:
        from orders.models import TransportOrder

        route = self._routes.get(order_id)
        if route is None:
            found = TransportOrder.objects.filter(vda_order_id=order_id).values_list(
                "route", flat=True
            )
            route = list(found.first() or [])
            if route:  # routes stay fixed once assigned (no traffic planning in this row)
                self._routes[order_id] = route
        index = sequence // 2
        return sequence % 2 == 0 and index < len(route) and route[index] == node


def judge(before: tuple[str, int] | None, sequence: int, *, of_order: bool) -> str:
    """One row against the highest id of its order seen before (`before`, None if none yet):
    "progress", "leftover" (the previous order's id before any progress) or "regression"."""
    if not of_order:
        return "leftover" if before is None else "regression"
    return "progress" if before is None or sequence >= before[1] else "regression"


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
                "regression_examples": watch.examples,
                "previous_order_sequence_samples": watch.leftovers,
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
