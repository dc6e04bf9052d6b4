"""Malformed and hostile input (RELIABILITY.md §3 row 6): a real `control` process on the row's
own broker and database gets N hostile state payloads for one vehicle (every class of
bench/faults/hostile.py), plus identity mismatches, garbage from made-up serial numbers, a
wrong major version and an unknown sub-topic.

Figures: sent per class, control's counters (from its log at SIGTERM), crashes (control not
alive), handler errors, vehicles registered by garbage, database tables whose row counts
changed, seconds until the next valid message shows in the database.
"""

import ast
import json
import re
import signal
import time
from typing import Any

import paho.mqtt.client as mqtt
from paho.mqtt.enums import CallbackAPIVersion

from bench.faults import hostile
from bench.faults.fleet import wait_until
from bench.faults.harness import row_context

VICTIM = "VICTIM-1"


def _table_counts() -> dict[str, int]:
    from django.db import connection

    counts = {}
    with connection.cursor() as cursor:
        for table in connection.introspection.table_names():
            cursor.execute(f'SELECT count(*) FROM "{table}"')  # noqa: S608 - our own table names
            counts[table] = cursor.fetchone()[0]
    return counts


def _settled_counts(quiet: float = 3.0, limit: float = 60.0) -> dict[str, int]:
    """`_table_counts` once they have not changed for `quiet` seconds: the floor observer
    (alerts, battery) writes what a state causes up to FLEET_OBSERVE_INTERVAL (2 s) after the
    flush, and that belongs to the valid state, not to the flood."""
    counts, since, deadline = _table_counts(), time.monotonic(), time.monotonic() + limit
    while time.monotonic() - since < quiet and time.monotonic() < deadline:
        time.sleep(0.5)
        now = _table_counts()
        if now != counts:
            counts, since = now, time.monotonic()
    return counts


def _victim_node() -> str | None:
    from robots.models import Vehicle

    return (
        Vehicle.objects.filter(serial_number=VICTIM).values_list("last_node_id", flat=True).first()
    )


def run(*, full: bool, scale: float = 1.0) -> dict[str, Any]:
    with row_context(full=full) as context:
        fleet = context.fleet
        count = context.pick(max(500, int(10_000 * scale)), 10_000)
        big = (1.5, 10.0, 100.0) if full else (1.5, 10.0)
        control = fleet.control()
        interface = fleet.interface
        state_topic = f"{interface}/v2/sim/{VICTIM}/state"
        attacker = mqtt.Client(callback_api_version=CallbackAPIVersion.VERSION2)
        attacker.max_queued_messages_set(0)
        attacker.max_inflight_messages_set(500)
        attacker.connect("127.0.0.1", context.stack.mosquitto.port)
        attacker.loop_start()

        def publish(topic: str, payload: bytes) -> mqtt.MQTTMessageInfo:
            return attacker.publish(topic, payload, qos=1)

        def register() -> bool:  # until control has subscribed and flushed the first state
            publish(state_topic, json.dumps(hostile.valid_state(VICTIM, 1, "a")).encode())
            return _victim_node() == "a"

        wait_until(register, 180, "victim registered", fleet)
        before = _settled_counts()
        sent: dict[str, int] = {"reject": 0, "accept": 0, "identity_mismatch": 0}
        sent.update({"made_up_serial": 0, "wrong_major_version": 0, "unknown_subtopic": 0})
        started = time.monotonic()
        last: mqtt.MQTTMessageInfo | None = None
        for index, (kind, payload) in enumerate(
            hostile.generate(VICTIM, count, context.rng, big=big)
        ):
            last = publish(state_topic, payload)
            sent[kind] += 1
            if index % 100 == 0:
                publish(state_topic, json.dumps(hostile.valid_state("EVIL", 5)).encode())
                publish(f"{interface}/v2/sim/GHOST-{index}/state", payload)
                publish(f"{interface}/v9/sim/{VICTIM}/state", payload)
                publish(f"{interface}/v2/sim/{VICTIM}/secrets", payload)
                sent["identity_mismatch"] += 1
                sent["made_up_serial"] += 1
                sent["wrong_major_version"] += 1
                sent["unknown_subtopic"] += 1
                last.wait_for_publish(60)  # keep the client's queue short
        final = json.dumps(hostile.valid_state(VICTIM, 2**31, "final")).encode()
        publish(state_topic, final).wait_for_publish(60)
        flood_s = time.monotonic() - started
        after_final = wait_until(
            lambda: _victim_node() == "final", 300, "final state applied", fleet
        )
        alive = control.alive()
        after = _settled_counts()  # one more flush of the counters, and the observer's pass
        attacker.loop_stop()
        attacker.disconnect()
        control.signal(signal.SIGTERM)
        code = control.popen.wait(60) if control.popen else None
        found = re.findall(r"control stopped; counters: (\{.*\})", control.output())
        counters = ast.literal_eval(found[-1]) if found else {}
        from robots.models import Vehicle

        serials = sorted(Vehicle.objects.values_list("serial_number", flat=True))
        changed = {t: (before[t], after.get(t)) for t in before if before[t] != after.get(t)}
        rejected = counters.get("decode_errors", 0) + counters.get("identity_mismatch", 0)
        rejected += counters.get("bad_topic", 0)
        expected_rejected = sent["reject"] + sent["identity_mismatch"] + sent["made_up_serial"]
        expected_rejected += sent["wrong_major_version"]
        figures: dict[str, Any] = {
            "hostile_payloads": sum(sent.values()),
            "sent": sent,
            "flood_s": round(flood_s, 1),
            "final_valid_state_in_db_s": round(after_final, 2),
            "control_alive_after_flood": alive,
            "control_exit_code": code,
            "counters": counters,
            "rejected_and_counted": rejected,
            "expected_rejected": expected_rejected,
            "handler_errors": counters.get("handler_errors", 0),
            # Everything that was neither refused nor a repeated header id was applied: the
            # states with unknown fields, the first and the final one.
            "applied": counters.get("messages", 0)
            - rejected
            - counters.get("duplicate", 0)
            - counters.get("stale", 0),
            "vehicles_registered": serials,
            "tables_changed": changed,
        }
        figures["passed"] = bool(
            alive
            and code == 0
            and rejected == expected_rejected
            and counters.get("handler_errors", 0) == 0
            and serials == [VICTIM]
            and set(changed) <= ALLOWED_CHANGES
            and figures["applied"] == sent["accept"] + 2
        )
        return figures


# Rows the valid messages (one in 50 carries unknown fields) legitimately add.
# alerts_alert: the one "protocol violations" alert control raises for the vehicle (shown,
# as it should be); the others: rows the valid states add (counters, battery samples).
ALLOWED_CHANGES = {"alerts_alert", "battery_batterysample", "maintenance_vehiclecounters"}
