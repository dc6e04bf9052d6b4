"""Vehicle link lost with an order in flight (RELIABILITY.md §3 row 4): each vehicle is its own
simulator process; one driving an order is SIGKILLed (socket closes: the broker sends its
will at once) or SIGSTOPped (silent: keepalive 15 s expires, then the will), then restarted
or SIGCONTed.

Figures: detection latency (signal → the vehicle no longer ONLINE in the database) p50/p95 per
kind, orders on two vehicles (observer) 0, orders lost, duplicate-content publishes.
"""

import signal
import time
from functools import partial
from typing import Any

from bench.faults.fleet import percentile, wait_until
from bench.faults.harness import Feeder, row_context, verdict, wait_all_closed, wait_online

VEHICLES = 3
KEEPALIVE_S = 15


def _connection(serial: str) -> str:
    from robots.models import Vehicle

    return Vehicle.objects.filter(serial_number=serial).values_list("connection", flat=True)[0]


def _driving_serials() -> list[str]:
    from orders.models import TransportOrder

    return list(
        TransportOrder.objects.filter(status="IN_PROGRESS").values_list(
            "vehicle__serial_number", flat=True
        )
    )


def _is(serial: str, connection: str) -> bool:
    return _connection(serial) == connection


def _is_not(serial: str, connection: str) -> bool:
    return _connection(serial) != connection


def _collect_driving(found: list[str], serials: set[str]) -> bool:
    found.extend(s for s in _driving_serials() if s in serials)
    return bool(found)


def run(*, full: bool, scale: float = 1.0) -> dict[str, Any]:
    with row_context(full=full) as context:
        fleet = context.fleet
        events = context.pick(max(2, int(6 * scale)), 100)
        fleet.control()
        fleet.worker(beat=True)
        simulators = {
            f"V{n}-1": fleet.simulator(f"sim{n}", count=1, prefix=f"V{n}-")
            for n in range(1, VEHICLES + 1)
        }
        wait_online(context, VEHICLES)
        feeder = Feeder(context, events * 3, in_flight=VEHICLES)
        feeder.start()
        detection: dict[str, list[float]] = {"SIGKILL": [], "SIGSTOP": []}
        for n in range(events):
            found: list[str] = []
            wait_until(
                partial(_collect_driving, found, set(simulators)),
                120,
                "a vehicle driving an order",
                fleet,
            )
            serial = found[0]
            process = simulators[serial]
            kind = "SIGKILL" if n % 2 == 0 else "SIGSTOP"
            hit = time.monotonic()
            if kind == "SIGKILL":
                process.kill()
            else:
                process.signal(signal.SIGSTOP)
            wait_until(partial(_is_not, serial, "ONLINE"), 120, f"{serial} detected")
            detection[kind].append(time.monotonic() - hit)
            if kind == "SIGKILL":
                process.start()
            else:
                process.signal(signal.SIGCONT)
            wait_until(partial(_is, serial, "ONLINE"), 120, f"{serial} back", fleet)
        feeder.join(timeout=events * 60)
        feeder.stop()
        drained = wait_all_closed(context, feeder.ids, timeout=300)
        figures = verdict(context, feeder.ids)
        limit = 1.5 * KEEPALIVE_S + 1
        figures.update(
            {
                "events": {k: len(v) for k, v in detection.items()},
                "detect_kill_s_p50": percentile(detection["SIGKILL"], 0.5),
                "detect_kill_s_p95": percentile(detection["SIGKILL"], 0.95),
                "detect_stop_s_p50": percentile(detection["SIGSTOP"], 0.5),
                "detect_stop_s_p95": percentile(detection["SIGSTOP"], 0.95),
                "detect_limit_s": limit,
                "drained_s": drained,
            }
        )
        worst = max(detection["SIGKILL"] + detection["SIGSTOP"], default=0)
        figures["passed"] = bool(
            figures["orders_sent_to_two_vehicles"] == 0
            and figures["duplicate_content_order_publishes"] == 0
            and figures["lost_orders"] == 0
            and (percentile(detection["SIGSTOP"], 0.95) or 0) <= limit
            and worst < 120
        )
        return figures
