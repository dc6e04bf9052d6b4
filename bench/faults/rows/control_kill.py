"""`control` SIGKILLed mid-order and restarted: it must resume from the vehicles' state (adopt
the orders they are driving) without duplicate or conflicting orders.

Figures: kills, orders lost, duplicate-content publishes, orders sent to two vehicles, time
from restart to the next order message published (resume) p50/p95.
"""

import contextlib
import signal
import time
from functools import partial
from typing import Any

from bench.faults.fleet import Observer, percentile, wait_until
from bench.faults.harness import Feeder, row_context, verdict, wait_all_closed, wait_online

VEHICLES = 3


def _published_more(observer: Observer, than: int) -> bool:
    return observer.order_publishes > than


def run(*, full: bool, scale: float = 1.0) -> dict[str, Any]:
    with row_context(full=full) as context:
        fleet, observer = context.fleet, context.observer
        orders = context.pick(max(4, int(24 * scale)), 200)
        kills = context.pick(max(1, int(4 * scale)), 20)
        control = fleet.control()
        fleet.worker(beat=True)
        fleet.simulator("simulator", count=VEHICLES)
        wait_online(context, VEHICLES)
        feeder = Feeder(context, orders, in_flight=VEHICLES + 1)
        feeder.start()
        resumes: list[float] = []
        for _ in range(kills):
            wait_until(lambda: observer.order_publishes > 0, 120, "an order published", fleet)
            time.sleep(context.rng.uniform(2, 6))
            control.signal(signal.SIGKILL)
            assert control.popen is not None
            control.popen.wait(30)
            time.sleep(context.rng.uniform(0, 3))
            published = observer.order_publishes
            control.start()
            # Nothing left to send is no failure: the verdict below still counts every order.
            with contextlib.suppress(TimeoutError):
                resumes.append(
                    wait_until(
                        partial(_published_more, observer, published),
                        90,
                        "an order after restart",
                    )
                )
        feeder.join(timeout=orders * 5)
        feeder.stop()
        drained = wait_all_closed(context, feeder.ids, timeout=300)
        figures = verdict(context, feeder.ids)
        figures.update(
            {
                "control_kills": kills,
                "resume_s_p50": percentile(resumes, 0.5),
                "resume_s_p95": percentile(resumes, 0.95),
                "resends_observed": figures["order_publishes"] - figures["order_messages_distinct"],
                "drained_s": drained,
                "feeder_errors": len(feeder.errors),
            }
        )
        figures["passed"] = bool(
            figures["nothing_lost"] and figures["all_finished"] and drained is not None
        )
        return figures
