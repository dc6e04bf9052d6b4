"""The link-loss row (RELIABILITY.md §3 row 4) in a short version: one vehicle SIGKILLed and
one SIGSTOPped mid-order, each a simulator process of its own, against the row's own services."""

from collections.abc import Callable
from typing import Any

import pytest

pytestmark = pytest.mark.e2e


def test_a_killed_and_a_frozen_vehicle_are_detected_in_time_and_keep_their_orders(
    run_row: Callable[..., dict[str, Any]],
) -> None:
    figures = run_row("link", scale=0.34, timeout=900)

    assert figures["events"] == {"SIGKILL": 1, "SIGSTOP": 1}
    # A killed vehicle's socket closes: the broker sends its will at once.
    assert figures["detected_as"]["SIGKILL"] == {"CONNECTIONBROKEN": 1}
    # A frozen one keeps its socket. It declares the VDA maximum of 30 s between states, so
    # its state timeout (35 s) and Mosquitto's will (22-29 s) would both be too late: control's
    # liveness probe (a stateRequest after 10 s of silence, 5 s to answer) notices it first.
    assert figures["state_interval_s"] == 30.0
    assert figures["detected_as"]["SIGSTOP"] == {"UNREACHABLE": 1}
    assert figures["detect_stop_s_max"] <= figures["detect_limit_s"]
    assert figures["will_after_stop_s_max"] > figures["detect_stop_s_max"]
    assert figures["detect_kill_s_p95"] <= figures["detect_limit_s"]
    assert figures["false_alarms"] == 0
    assert figures["orders_sent_to_two_vehicles"] == 0
    assert figures["duplicate_content_order_publishes"] == 0
    assert figures["lost_orders"] == 0
    assert figures["passed"]
