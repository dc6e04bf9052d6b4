"""Clock skew (RELIABILITY.md §3 row 8): vehicle timestamps must never order anything.

Simulated vehicles stamp every state 5 minutes in the past while they drive orders; an injected
vehicle publishes states stamped +5 min, +1 day, and without a zone ("no Z"), in turn. Header
ids and receive time decide; the skew is measured and shown.

Figures: orders lost; states of the injected vehicle applied in header-id order (its stored last
node is the last one sent); false offline flips (a vehicle leaving ONLINE) 0; measured skew per
vehicle.
"""

import json
import threading
import time
from datetime import UTC, datetime, timedelta
from typing import Any

import paho.mqtt.client as mqtt
from paho.mqtt.enums import CallbackAPIVersion

from bench.faults.fleet import wait_until
from bench.faults.harness import Feeder, row_context, verdict, wait_all_closed, wait_online
from bench.faults.hostile import valid_state

VEHICLES = 2
BEHIND_S = 300
SKEWED = "SKEW-1"


def _stamp(index: int) -> str:
    now = datetime.now(UTC)
    mode = index % 3
    if mode == 0:
        return (
            (now + timedelta(minutes=5)).isoformat(timespec="milliseconds").replace("+00:00", "Z")
        )
    if mode == 1:
        return (now + timedelta(days=1)).isoformat(timespec="milliseconds").replace("+00:00", "Z")
    return now.replace(tzinfo=None).isoformat(timespec="milliseconds")  # no zone at all


class FlipWatch(threading.Thread):
    """Counts vehicles leaving ONLINE (none should: skew is no reason to go offline)."""

    def __init__(self) -> None:
        super().__init__(daemon=True)
        self.halt = threading.Event()
        self.flips: list[tuple[str, str]] = []

    def run(self) -> None:
        from django.db import connection

        from robots.models import Vehicle

        before: dict[str, str] = {}
        while not self.halt.wait(0.3):
            for serial, state in Vehicle.objects.values_list("serial_number", "connection"):
                if before.get(serial) == "ONLINE" and state != "ONLINE":
                    self.flips.append((serial, state))
                before[serial] = state
        connection.close()


def run(*, full: bool, scale: float = 1.0) -> dict[str, Any]:
    with row_context(full=full) as context:
        from robots.models import Vehicle

        fleet = context.fleet
        orders = context.pick(max(3, int(12 * scale)), 100)
        fleet.control()
        fleet.worker(beat=True)
        misbehave = f"stale_states=1,stale_age={BEHIND_S}"
        extra = [a for n in range(1, VEHICLES + 1) for a in ("--misbehave", f"AGV-{n}:{misbehave}")]
        fleet.simulator("simulator", count=VEHICLES, extra=tuple(extra))
        wait_online(context, VEHICLES)
        skewed = mqtt.Client(callback_api_version=CallbackAPIVersion.VERSION2)
        skewed.connect("127.0.0.1", context.stack.mosquitto.port)
        skewed.loop_start()
        base = f"{fleet.interface}/v2/sim/{SKEWED}"
        online = {"headerId": 1, "timestamp": _stamp(1), "version": "2.0.0", "manufacturer": "sim"}
        online.update({"serialNumber": SKEWED, "connectionState": "ONLINE"})
        skewed.publish(f"{base}/connection", json.dumps(online), qos=1, retain=True)
        watch = FlipWatch()
        watch.start()
        feeder = Feeder(context, orders, in_flight=VEHICLES + 1)
        feeder.start()
        sent = 0
        while feeder.is_alive() or sent < 30:
            sent += 1
            state = valid_state(SKEWED, sent, f"n{sent}")
            state["timestamp"] = _stamp(sent)
            skewed.publish(f"{base}/state", json.dumps(state), qos=0)
            time.sleep(1.0)
        feeder.stop()
        drained = wait_all_closed(context, feeder.ids, timeout=300)
        applied = wait_until(
            lambda: Vehicle.objects.filter(serial_number=SKEWED, last_node_id=f"n{sent}").exists(),
            30,
            "the last skewed state applied",
        )
        watch.halt.set()
        watch.join(5)
        skewed.loop_stop()
        skewed.disconnect()
        figures = verdict(context, feeder.ids)
        skews = dict(Vehicle.objects.values_list("serial_number", "clock_skew"))
        behind = [skews.get(f"AGV-{n}") for n in range(1, VEHICLES + 1)]
        figures.update(
            {
                "skewed_states_sent": sent,
                "last_skewed_state_applied_s": round(applied, 2),
                "false_offline_flips": len(watch.flips),
                "flips": watch.flips[:10],
                "measured_skew_s": {
                    k: (round(v, 1) if v is not None else None) for k, v in skews.items()
                },
                "drained_s": drained,
            }
        )
        figures["passed"] = bool(
            figures["nothing_lost"]
            and figures["all_finished"]
            and not watch.flips
            and all(s is not None and abs(s - BEHIND_S) < 30 for s in behind)
        )
        return figures
