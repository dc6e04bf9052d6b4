"""Short versions of the fault rows (RELIABILITY.md §3/§5), each against its own services:
the figures must show nothing lost and no duplicate-content publish."""

from collections.abc import Callable
from typing import Any

import pytest

pytestmark = pytest.mark.e2e

Row = Callable[..., dict[str, Any]]


def test_broker_sigkill_and_sigterm_mid_order_lose_nothing(run_row: Row) -> None:
    figures = run_row("broker", scale=0.15)

    assert figures["restarts"] == {"SIGKILL": 1, "SIGTERM": 1}
    assert figures["lost_orders"] == 0
    assert figures["incomplete_histories"] == 0
    assert figures["duplicate_content_order_publishes"] == 0
    assert figures["orders_sent_to_two_vehicles"] == 0
    assert figures["recovery_s_p95"] <= 35
    assert figures["passed"]


def test_control_sigkill_and_restart_resumes_without_duplicate_orders(run_row: Row) -> None:
    figures = run_row("control", scale=0.25)

    assert figures["control_kills"] >= 1
    assert figures["lost_orders"] == 0
    assert figures["duplicate_content_order_publishes"] == 0
    assert figures["duplicate_content_instant_actions"] == 0
    assert figures["orders_sent_to_two_vehicles"] == 0
    assert figures["passed"]


def test_postgresql_down_the_api_answers_503_and_loses_no_acknowledged_order(
    run_row: Row,
) -> None:
    figures = run_row("database", scale=0.5)

    assert figures["http_500s"] == 0
    assert figures["http_503s"] + figures["requests_by_status"].get("0", 0) > 0  # it was down
    assert figures["retry_after_missing"] == 0
    assert figures["acknowledged_orders"] > 0
    assert figures["acknowledged_lost"] == 0
    assert figures["half_written_orders"] == 0
    assert all(figures["processes_alive"].values())
    assert figures["passed"]


def test_worker_and_pool_child_killed_during_dispatch_lose_no_order(run_row: Row) -> None:
    figures = run_row("worker", scale=0.2)

    assert figures["kills"] == {"child": 1, "worker": 1}
    assert figures["lost_orders"] == 0
    assert figures["duplicate_content_order_publishes"] == 0
    assert figures["orders_sent_to_two_vehicles"] == 0
    assert figures["assigned_s_max"] <= 60
    assert figures["passed"]


def test_ten_thousand_hostile_payloads_are_counted_and_control_lives(run_row: Row) -> None:
    figures = run_row("malformed", scale=1.0)

    assert figures["hostile_payloads"] >= 10_000
    assert figures["control_alive_after_flood"]
    assert figures["control_exit_code"] == 0
    assert figures["rejected_and_counted"] == figures["expected_rejected"]
    assert figures["handler_errors"] == 0
    assert figures["vehicles_registered"] == ["VICTIM-1"]  # garbage registers nobody
    assert figures["sent"]["accept"] > 0  # unknown fields tolerated: those states applied
    assert figures["passed"]
