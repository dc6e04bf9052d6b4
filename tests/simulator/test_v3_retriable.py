"""A simulated 3.0 vehicle and retriable actions (REFERENCE §3 E.27): a failing `retriable`
order action waits in RETRIABLE for the master's retry or skipRetry."""

from __future__ import annotations

from simulator import wire
from simulator.misbehaviour import Misbehaviour
from simulator.vehicle import VirtualVehicle
from tests.simulator.builders import (
    action,
    error_types,
    finished,
    instant3,
    make_order3,
    make_vehicle,
    run3,
    run3_until,
    send3,
)
from vda5050 import v3
from vda5050.enums import BlockingType


def _pick_fails(fail_count: int | None = 1) -> VirtualVehicle:
    vehicle = make_vehicle(version="3.0.0")
    vehicle.misbehave(Misbehaviour(fail_actions=("pick",), fail_count=fail_count))
    pick = action("pick", "p1", BlockingType.HARD, loadId="L1", loadType="EPAL")
    order = make_order3("o1", ["n1", "n2", "n3"], actions={"n2": [pick]})
    order.nodes[1].actions[0].retriable = True
    assert send3(vehicle, order)
    return vehicle


def _pick(vehicle: VirtualVehicle) -> v3.ActionState:
    (state,) = wire.states(vehicle)
    assert isinstance(state, v3.State)
    (pick,) = [a for a in state.action_states if a.action_id == "p1"]
    return pick


def _retriable(vehicle: VirtualVehicle) -> bool:
    run = vehicle.actions.get("p1")
    return run is not None and run.retriable


def test_a_failing_retriable_action_waits_in_retriable_and_the_vehicle_stands() -> None:
    vehicle = _pick_fails()
    run3_until(vehicle, _retriable)
    where = vehicle.last_node_id
    run3(vehicle, 2.0)

    pick = _pick(vehicle)
    assert pick.action_status == v3.ActionStatus.RETRIABLE
    assert pick.action_result == "pick failed (simulated misbehaviour)"
    assert vehicle.last_node_id == where == "n2"  # HARD: no driving while it waits
    assert not vehicle.driving


def test_retry_runs_it_again_and_the_order_finishes() -> None:
    vehicle = _pick_fails(fail_count=1)
    run3_until(vehicle, _retriable)

    send3(vehicle, instant3(action("retry", "r1", actionId="p1")))
    run3_until(vehicle, finished)

    assert _pick(vehicle).action_status == v3.ActionStatus.FINISHED
    assert vehicle.last_node_id == "n3"


def test_skip_retry_fails_it_and_the_order_goes_on() -> None:
    vehicle = _pick_fails(fail_count=None)
    run3_until(vehicle, _retriable)

    send3(vehicle, instant3(action("skipRetry", "s1", actionId="p1")))
    run3_until(vehicle, finished)

    pick = _pick(vehicle)
    assert (pick.action_status, pick.action_result) == (
        v3.ActionStatus.FAILED,
        "pick failed (simulated misbehaviour)",
    )
    assert vehicle.last_node_id == "n3"


def test_retry_of_an_action_that_is_not_retriable_is_an_invalid_instant_action() -> None:
    vehicle = _pick_fails()

    send3(vehicle, instant3(action("retry", "r1", actionId="p1")))

    assert "INVALID_INSTANT_ACTION" in error_types(vehicle)
    assert vehicle.actions.get("r1").status.value == "FAILED"  # type: ignore[union-attr]


def test_cancel_order_fails_a_retriable_action_and_finishes() -> None:
    vehicle = _pick_fails(fail_count=None)
    run3_until(vehicle, _retriable)

    send3(vehicle, instant3(action("cancelOrder", "c1")))
    run3_until(vehicle, lambda v: v.actions.get("c1").status.value == "FINISHED")  # type: ignore[union-attr]

    assert _pick(vehicle).action_status == v3.ActionStatus.FAILED


def test_without_retriable_a_failure_is_final_as_before() -> None:
    vehicle = make_vehicle(version="3.0.0")
    vehicle.misbehave(Misbehaviour(fail_actions=("pick",)))
    pick = action("pick", "p1", BlockingType.HARD, loadId="L1", loadType="EPAL")
    send3(vehicle, make_order3("o1", ["n1", "n2", "n3"], actions={"n2": [pick]}))

    run3_until(vehicle, finished)

    assert _pick(vehicle).action_status == v3.ActionStatus.FAILED
