"""Broker restart mid-order (RELIABILITY.md §3 row 1): the row's Mosquitto is SIGTERMed or
SIGKILLed (alternately) while orders run, and restarted after 0 / 5 / 30 s.

Figures: orders lost, duplicate-content publishes, recovery time (broker up → a fresh state
from every vehicle, as the independent observer sees it) p50/p95, resends (publishes of a
message already published).
"""

import signal
import time
from functools import partial
from typing import Any

from bench.faults.fleet import Observer, percentile, wait_until
from bench.faults.harness import Feeder, row_context, verdict, wait_all_closed, wait_online

VEHICLES = 4


def _all_fresh(observer: Observer, serials: set[str], since: float) -> bool:
    return all(observer.state_seen.get(s, 0) > since for s in serials)


def run(*, full: bool, scale: float = 1.0) -> dict[str, Any]:
    with row_context(full=full) as context:
        fleet, observer, broker = context.fleet, context.observer, context.stack.mosquitto
        orders = context.pick(max(4, int(30 * scale)), 500)
        cycles = context.pick(max(2, int(4 * scale)), 20)
        delays = [0.0, 5.0, 30.0] if full else [0.0, 5.0 * min(1.0, scale)]
        fleet.control()
        fleet.worker(beat=True)
        fleet.simulator("simulator", count=VEHICLES)
        wait_online(context, VEHICLES)
        feeder = Feeder(context, orders, in_flight=VEHICLES + 2)
        feeder.start()
        recoveries: list[float] = []
        kills: dict[str, int] = {"SIGKILL": 0, "SIGTERM": 0}
        for cycle in range(cycles):
            time.sleep(context.rng.uniform(3, 8))
            sig = signal.SIGKILL if cycle % 2 == 0 else signal.SIGTERM
            broker.signal(sig)
            kills[sig.name] += 1
            time.sleep(delays[cycle % len(delays)])
            broker.start()
            up = time.monotonic()
            serials = set(observer.state_seen)
            wait_until(
                partial(_all_fresh, observer, serials, up),
                120,
                "a fresh state from every vehicle",
                fleet,
            )
            recoveries.append(max(observer.state_seen[s] for s in serials) - up)
        feeder.join(timeout=orders * 5)
        feeder.stop()
        drained = wait_all_closed(context, feeder.ids, timeout=300)
        figures = verdict(context, feeder.ids)
        figures.update(
            {
                "restarts": kills,
                "delays_s": delays,
                "recovery_s_p50": percentile(recoveries, 0.5),
                "recovery_s_p95": percentile(recoveries, 0.95),
                "recovery_s_max": percentile(recoveries, 1.0),
                "resends_observed": figures["order_publishes"] - figures["order_messages_distinct"],
                "drained_s": drained,
                "feeder_errors": len(feeder.errors),
                "processes_alive": all(p.alive() for p in fleet.processes.values()),
            }
        )
        figures["passed"] = bool(
            figures["nothing_lost"]
            and figures["all_finished"]
            and figures["processes_alive"]
            and (figures["recovery_s_p95"] or 0) <= 35
        )
        return figures
