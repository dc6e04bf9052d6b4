"""The simulator honours what master control sends, built the way control/order_messages.py
builds it: route node i has sequenceId 2·i, the edge into it 2·i−1, and an update repeats the
last base node (same nodeId, sequenceId and actions) as its stitching node."""

from __future__ import annotations

import logging

import pytest

from simulator.actions import CATALOGUE
from tests.simulator.builders import (
    action,
    edge,
    error_types,
    finished,
    instant,
    make_vehicle,
    node,
    run,
    run_until,
    status,
)
from vda5050 import Order
from vda5050.enums import ActionScope, ActionStatus

ROUTE = ["n1", "n2", "n3", "n4", "n5"]
PICK = action("pick", "pick-1", loadId="L1", loadType="EPAL", stationType="floor")
DROP = action("drop", "drop-1", loadType="EPAL", stationType="floor")


def master_order(first: int, last: int, released: int, update_id: int) -> Order:
    """Route indices first..last, released up to ``released``: pick at n3, drop at the end."""
    nodes, edges = [], []
    for i in range(first, last + 1):
        if i > first:
            edges.append(edge(2 * i - 1, ROUTE[i - 1], ROUTE[i], released=i <= released))
        actions = [PICK] if i == 2 else [DROP] if i == len(ROUTE) - 1 else []
        nodes.append(node(2 * i, ROUTE[i], released=i <= released, actions=actions))
    return Order(
        header_id=update_id,
        timestamp="2024-01-01T00:00:00.00Z",
        version="2.0.0",
        manufacturer="sim",
        serial_number="AGV-1",
        order_id="transport-7",
        order_update_id=update_id,
        nodes=nodes,
        edges=edges,
    )


def test_master_base_extension_with_actions_on_the_stitching_node() -> None:
    vehicle = make_vehicle()
    initial = master_order(0, 4, released=2, update_id=0)
    assert vehicle.on_order(initial)
    run_until(vehicle, lambda v: status(v, "pick-1") is ActionStatus.FINISHED)
    run(vehicle, 5.0)
    # At the decision point n3 with a horizon left: standing still, asking for a new base.
    state = vehicle.build_state()
    assert (state.last_node_id, state.last_node_sequence_id, state.driving) == ("n3", 4, False)
    assert [(n.node_id, n.released) for n in state.node_states] == [("n4", False), ("n5", False)]
    assert state.new_base_request is True

    # An unconfirmed order is resent identically: ignored, no error, nothing re-run.
    assert not vehicle.on_order(initial)
    assert error_types(vehicle) == []
    assert status(vehicle, "pick-1") is ActionStatus.FINISHED

    # The update repeats n3 (seq 4) with its pick; the pick must not run again.
    update = master_order(2, 4, released=4, update_id=1)
    assert vehicle.on_order(update)
    state = vehicle.build_state()
    assert state.order_update_id == 1
    assert state.new_base_request is False
    assert [(n.node_id, n.sequence_id, n.released) for n in state.node_states] == [
        ("n4", 6, True),
        ("n5", 8, True),
    ]
    assert not vehicle.on_order(update)  # resend of the update: ignored too
    run_until(vehicle, finished)
    assert (vehicle.last_node_id, vehicle.last_node_sequence_id) == ("n5", 8)
    assert [a.action_id for a in vehicle.build_state().action_states] == ["pick-1", "drop-1"]
    assert status(vehicle, "drop-1") is ActionStatus.FINISHED
    assert vehicle.loads == []
    assert error_types(vehicle) == []


def test_master_extends_the_base_step_by_step_while_driving() -> None:
    vehicle = make_vehicle()
    assert vehicle.on_order(master_order(0, 4, released=1, update_id=0))
    for update_id, released in enumerate((2, 3, 4), start=1):
        run(vehicle, 1.0)
        assert vehicle.on_order(master_order(released - 1, 4, released, update_id))
    run_until(vehicle, finished)
    assert (vehicle.last_node_id, vehicle.order_update_id) == ("n5", 3)
    assert error_types(vehicle) == []


def test_horizon_is_never_driven() -> None:
    vehicle = make_vehicle()
    vehicle.on_order(master_order(0, 4, released=0, update_id=0))
    run(vehicle, 30.0)
    assert (vehicle.x, vehicle.y, vehicle.last_node_id) == (0.0, 0.0, "n1")
    assert vehicle.build_state().new_base_request is True


def test_log_report_finishes_at_once_and_is_declared(caplog: pytest.LogCaptureFixture) -> None:
    caplog.set_level(logging.INFO)
    vehicle = make_vehicle()
    vehicle.on_instant_actions(instant(action("logReport", "log-1", reason="stuck at n3")))
    assert status(vehicle, "log-1") is ActionStatus.FINISHED
    assert "logReport: stuck at n3" in caplog.text
    vehicle.on_instant_actions(instant(action("logReport", "log-2")))
    assert status(vehicle, "log-2") is ActionStatus.FAILED  # reason is required
    spec = CATALOGUE["logReport"]
    assert spec.scopes == (ActionScope.INSTANT,)
    assert spec.required_keys == {"reason"}
    declared = {a.action_type for a in vehicle.build_factsheet().protocol_features.agv_actions}
    assert "logReport" in declared


def test_pause_holds_the_order_and_stop_pause_resumes_it() -> None:
    vehicle = make_vehicle()
    vehicle.on_order(master_order(0, 4, released=4, update_id=0))
    run(vehicle, 1.0)
    vehicle.on_instant_actions(instant(action("startPause", "pause-1")))
    run(vehicle, 5.0)
    state = vehicle.build_state()
    assert (state.paused, state.driving) == (True, False)
    assert vehicle.last_node_id == "n1"
    vehicle.on_instant_actions(instant(action("stopPause", "pause-2")))
    run_until(vehicle, finished)
    assert vehicle.last_node_id == "n5"
