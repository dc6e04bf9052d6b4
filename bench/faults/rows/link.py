"""Vehicle link lost with an order in flight (RELIABILITY.md §3 row 4): each vehicle is its own
simulator process; one driving an order is SIGKILLed (socket closes: the broker sends its
will at once) or SIGSTOPped (radio loss: the socket stays open), then restarted or SIGCONTed.

Two paths can notice a frozen (SIGSTOPped) vehicle, and the row times both:
- control (`control/session.py`): silent for LIVENESS_PROBE_AFTER (10 s) → one stateRequest;
  no state within 5 s → UNREACHABLE (else its state timeout: the factsheet's
  `defaultStateInterval` + 5 s). The vehicles here declare STATE_INTERVAL_S, the VDA maximum.
- the broker's will: Mosquitto 2.0 drops a silent client only when its keepalive sweep (at most
  every 6 s: `last_keepalive_check + 5 < now`, whole seconds) finds it silent for more than
  keepalive*3/2 (integer) = 22 s, i.e. 22-29 s after the last packet; then CONNECTIONBROKEN.
The §5 goal (p95 ≤ 1.5 × keepalive + 1 s) is judged on the first of them (what dispatch sees);
the will's latency is reported beside it (see docs/RELIABILITY_RESULTS.md, link loss).

Figures: detection latency (signal → the vehicle no longer ONLINE in the database) p50/p95/max
per kind and which state detected it, the will's latency after SIGSTOP, vehicles that were
not hit but seen not ONLINE (false alarms), orders on two vehicles (observer) 0, orders lost,
duplicate-content publishes.
"""

import signal
import threading
import time
from collections import Counter
from functools import partial
from typing import Any

from bench.faults.fleet import Fleet, Process, percentile, wait_until
from bench.faults.harness import Feeder, row_context, verdict, wait_all_closed, wait_online

VEHICLES = 3
KEEPALIVE_S = 15  # simulator.mqtt.KEEPALIVE_SECONDS, REFERENCE §2 "around 15 s"
# Declared in the vehicles' factsheets (defaultStateInterval): VDA's 30 s maximum, the worst
# case: only control's liveness probe (stateRequest after 10 s of silence) comes before the will.
STATE_INTERVAL_S = 30.0


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


def _not_online(serial: str, seen: list[str]) -> bool:
    connection = _connection(serial)
    seen.append(connection)
    return connection != "ONLINE"


def _collect_driving(found: list[str], serials: set[str]) -> bool:
    found.extend(s for s in _driving_serials() if s in serials)
    return bool(found)


class FalseAlarms(threading.Thread):
    """Counts vehicles that were not hit but went from ONLINE to anything else (a state
    timeout or a probe too tight for the vehicles' real cadence would show here)."""

    def __init__(self, serials: set[str]) -> None:
        super().__init__(daemon=True)
        self.serials = serials
        self.hit: set[str] = set()  # under fault: from the signal until back ONLINE
        self.alarms: list[tuple[str, str]] = []
        self._halt = threading.Event()

    def run(self) -> None:
        from django.db import connection

        from robots.models import Vehicle

        online: set[str] = set()
        try:
            while not self._halt.wait(0.5):
                rows = Vehicle.objects.filter(serial_number__in=self.serials)
                now = dict(rows.values_list("serial_number", "connection"))
                hit = set(self.hit)
                for serial, state in now.items():
                    if state == "ONLINE":
                        online.add(serial)
                    elif serial in online:
                        online.discard(serial)
                        if serial not in hit:
                            self.alarms.append((serial, state))
        finally:
            connection.close()

    def stop(self) -> None:
        self._halt.set()
        self.join(10)


def _event(
    fleet: Fleet,
    simulators: dict[str, Process],
    alarms: FalseAlarms,
    kind: str,
    detection: dict[str, list[float]],
    detected_as: dict[str, Counter[str]],
    will_after_stop: list[float],
) -> None:
    """Hit one vehicle driving an order with `kind`, time the detection, bring it back."""
    found: list[str] = []
    wait_until(
        partial(_collect_driving, found, set(simulators)), 120, "a vehicle driving an order", fleet
    )
    serial = found[0]
    process = simulators[serial]
    alarms.hit.add(serial)
    hit = time.monotonic()
    if kind == "SIGKILL":
        process.kill()
    else:
        process.signal(signal.SIGSTOP)
    seen: list[str] = []
    wait_until(partial(_not_online, serial, seen), 120, f"{serial} detected")
    detection[kind].append(time.monotonic() - hit)
    detected_as[kind][seen[-1]] += 1
    if kind == "SIGKILL":
        process.start()
    else:
        # Keep it frozen until the broker's will is in too: both paths are timed.
        wait_until(partial(_is, serial, "CONNECTIONBROKEN"), 120, f"{serial} will")
        will_after_stop.append(time.monotonic() - hit)
        process.signal(signal.SIGCONT)
    wait_until(partial(_is, serial, "ONLINE"), 120, f"{serial} back", fleet)
    alarms.hit.discard(serial)


def run(*, full: bool, scale: float = 1.0) -> dict[str, Any]:
    with row_context(full=full) as context:
        fleet = context.fleet
        events = context.pick(max(2, int(6 * scale)), 100)
        fleet.control()
        fleet.worker(beat=True)
        extra = ("--state-interval", str(STATE_INTERVAL_S))
        simulators = {
            f"V{n}-1": fleet.simulator(f"sim{n}", count=1, prefix=f"V{n}-", extra=extra)
            for n in range(1, VEHICLES + 1)
        }
        wait_online(context, VEHICLES)
        alarms = FalseAlarms(set(simulators))
        alarms.start()
        # Work until the last event: a fixed number of orders may all be done before it.
        feeder = Feeder(context, events * 20, in_flight=VEHICLES)
        feeder.start()
        detection: dict[str, list[float]] = {"SIGKILL": [], "SIGSTOP": []}
        detected_as: dict[str, Counter[str]] = {"SIGKILL": Counter(), "SIGSTOP": Counter()}
        will_after_stop: list[float] = []
        try:
            for n in range(events):
                kind = "SIGKILL" if n % 2 == 0 else "SIGSTOP"
                _event(fleet, simulators, alarms, kind, detection, detected_as, will_after_stop)
                print(f"event {n + 1}/{events} {kind}: {detection[kind][-1]:.1f} s", flush=True)
        finally:
            feeder.stop()
            alarms.stop()
        drained = wait_all_closed(context, feeder.ids, timeout=300)
        figures = verdict(context, feeder.ids)
        limit = 1.5 * KEEPALIVE_S + 1
        kill_p95 = percentile(detection["SIGKILL"], 0.95) or 0
        stop_p95 = percentile(detection["SIGSTOP"], 0.95) or 0
        figures.update(
            {
                "events": {k: len(v) for k, v in detection.items()},
                "keepalive_s": KEEPALIVE_S,
                "state_interval_s": STATE_INTERVAL_S,
                "detect_kill_s_p50": percentile(detection["SIGKILL"], 0.5),
                "detect_kill_s_p95": kill_p95,
                "detect_kill_s_max": round(max(detection["SIGKILL"], default=0), 3),
                "detect_stop_s_p50": percentile(detection["SIGSTOP"], 0.5),
                "detect_stop_s_p95": stop_p95,
                "detect_stop_s_max": round(max(detection["SIGSTOP"], default=0), 3),
                "detected_as": {k: dict(v) for k, v in detected_as.items()},
                "will_after_stop_s_p50": percentile(will_after_stop, 0.5),
                "will_after_stop_s_p95": percentile(will_after_stop, 0.95),
                "will_after_stop_s_max": round(max(will_after_stop, default=0), 3),
                "detect_limit_s": limit,
                "false_alarms": len(alarms.alarms),
                "false_alarm_examples": alarms.alarms[:5],
                "drained_s": drained,
            }
        )
        figures["passed"] = bool(
            figures["orders_sent_to_two_vehicles"] == 0
            and figures["duplicate_content_order_publishes"] == 0
            and figures["lost_orders"] == 0
            and kill_p95 <= limit
            and stop_p95 <= limit
            and not alarms.alarms
        )
        return figures
