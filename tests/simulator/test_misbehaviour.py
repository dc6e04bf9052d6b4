"""Scripted misbehaviour on VirtualVehicle with a fake clock (no MQTT)."""

from __future__ import annotations

import logging
from datetime import UTC, datetime

import pytest

from simulator import Misbehaviour
from simulator.vehicle import VirtualVehicle
from tests.simulator.builders import (
    action,
    error_types,
    finished,
    instant,
    make_order,
    make_vehicle,
    run,
    run_until,
    status,
)
from vda5050 import State
from vda5050.enums import ActionStatus, ErrorLevel, OperatingMode
from vda5050.headers import parse_timestamp


def _vehicle(time_scale: float = 1.0, **misbehaviour: object) -> VirtualVehicle:
    plan = Misbehaviour(**misbehaviour)  # type: ignore[arg-type]
    return make_vehicle(misbehaviour=plan, time_scale=time_scale)


def _refs(state: State, index: int = 0) -> dict[str, str]:
    return {r.reference_key: r.reference_value for r in state.errors[index].error_references or []}


def _fired(caplog: pytest.LogCaptureFixture, key: str) -> list[str]:
    return [
        r.getMessage()
        for r in caplog.records
        if r.levelno == logging.INFO and f"misbehaviour {key}" in r.getMessage()
    ]


# ---------------------------------------------------------------------------- rejection
def test_rejects_the_next_n_orders_then_accepts(caplog: pytest.LogCaptureFixture) -> None:
    caplog.set_level(logging.INFO)
    vehicle = _vehicle(reject_orders="orderError", reject_count=2)
    assert not vehicle.on_order(make_order("o1", ["n1", "n2"], update_id=0))
    state = vehicle.build_state()
    assert (state.order_id, state.node_states) == ("", [])
    assert [(e.error_type, e.error_level) for e in state.errors] == [
        ("orderError", ErrorLevel.WARNING)
    ]
    assert _refs(state) == {"orderId": "o1", "orderUpdateId": "0"}
    assert not vehicle.on_order(make_order("o2", ["n1", "n2"]))
    assert error_types(vehicle) == ["orderError", "orderError"]
    assert vehicle.on_order(make_order("o3", ["n1", "n2"]))
    assert error_types(vehicle) == []
    assert len(_fired(caplog, "reject_orders")) == 2


def test_rejects_every_update_with_a_vendor_error_and_the_old_order_continues() -> None:
    vehicle = make_vehicle()
    assert vehicle.on_order(make_order("o1", ["n1", "n2", "n3"], released=2))
    vehicle.misbehave(Misbehaviour(reject_orders="updateRefused"))
    for update_id in (1, 2):
        update = make_order("o1", ["n2", "n3"], update_id=update_id, first_seq=2)
        assert not vehicle.on_order(update)
    state = vehicle.build_state()
    assert (state.order_id, state.order_update_id) == ("o1", 0)
    assert [e.error_type for e in state.errors] == ["updateRefused", "updateRefused"]
    assert _refs(state, 1) == {"orderId": "o1", "orderUpdateId": "2"}
    run(vehicle, 10)
    assert vehicle.last_node_id == "n2"  # base still driven, horizon not


def test_resend_of_the_accepted_order_is_not_rejected() -> None:
    vehicle = make_vehicle()
    order = make_order("o1", ["n1", "n2"])
    assert vehicle.on_order(order)
    vehicle.misbehave(Misbehaviour(reject_orders="validationError", reject_count=1))
    assert not vehicle.on_order(order)
    assert error_types(vehicle) == []
    assert not vehicle.on_order(make_order("o1", ["n2", "n3"], update_id=1, first_seq=2))
    assert error_types(vehicle) == ["validationError"]


# ---------------------------------------------------------------------------- drop and delay
def test_dropped_orders_leave_no_trace(caplog: pytest.LogCaptureFixture) -> None:
    caplog.set_level(logging.INFO)
    vehicle = _vehicle(drop_orders=2)
    vehicle.take_state_due()
    order = make_order("o1", ["n1", "n2"])
    assert not vehicle.on_order(order)
    assert not vehicle.on_order(order)
    assert not vehicle.take_state_due()  # no state is published for a dropped order
    state = vehicle.build_state()
    assert (state.order_id, state.errors, state.node_states) == ("", [], [])
    assert vehicle.on_order(order)  # the master's third send gets through
    assert vehicle.take_state_due()
    assert vehicle.build_state().order_id == "o1"
    assert len(_fired(caplog, "drop_orders")) == 2


def test_delayed_order_is_accepted_after_simulated_seconds(
    caplog: pytest.LogCaptureFixture,
) -> None:
    caplog.set_level(logging.INFO)
    vehicle = _vehicle(delay_orders=3.0, time_scale=2.0)
    order = make_order("o1", ["n1", "n2"])
    assert not vehicle.on_order(order)
    assert vehicle.build_state().order_id == ""
    run(vehicle, 1.0)  # 2 s simulated
    assert not vehicle.on_order(order)  # resend while waiting: ignored, not queued twice
    assert vehicle.build_state().order_id == ""
    assert error_types(vehicle) == []
    run(vehicle, 0.6)  # 3.2 s simulated
    state = vehicle.build_state()
    assert (state.order_id, [n.node_id for n in state.node_states]) == ("o1", ["n2"])
    assert vehicle.saboteur.due_orders() == []
    assert len(_fired(caplog, "delay_orders: order o1/0 waits")) == 1
    assert len(_fired(caplog, "delay_orders: processing order o1/0")) == 1
    run_until(vehicle, finished)
    assert vehicle.last_node_id == "n2"


def test_delayed_update_is_checked_when_processed() -> None:
    vehicle = make_vehicle()
    vehicle.on_order(make_order("o1", ["n1", "n2", "n3"], released=2))
    vehicle.misbehave(Misbehaviour(delay_orders=5.0))
    assert not vehicle.on_order(make_order("o1", ["n2", "n3"], update_id=1, first_seq=2))
    run(vehicle, 4.9)
    assert vehicle.order_update_id == 0
    assert [n.released for n in vehicle.build_state().node_states] == [True, False]
    run(vehicle, 0.2)
    assert vehicle.order_update_id == 1
    run_until(vehicle, finished)
    assert vehicle.last_node_id == "n3"


# ---------------------------------------------------------------------------- states
def test_duplicate_states_repeat_the_header_id() -> None:
    vehicle = _vehicle(duplicate_states=1.0)
    states = vehicle.build_states()
    assert [s.header_id for s in states] == [0, 0]
    assert states[0] is states[1]
    assert [s.header_id for s in vehicle.build_states()] == [1, 1]


def test_reordered_state_follows_the_newer_one() -> None:
    vehicle = _vehicle(reorder_states=1.0)
    assert vehicle.build_states() == []  # state 0 held back
    assert vehicle.take_state_due()  # ... and the next state is due at once
    assert [s.header_id for s in vehicle.build_states()] == [1, 0]
    assert vehicle.build_states() == []
    assert [s.header_id for s in vehicle.build_states()] == [3, 2]


def test_stale_states_carry_an_old_timestamp() -> None:
    vehicle = _vehicle(stale_states=1.0, stale_age=120.0)
    state = vehicle.build_states()[0]
    age = (datetime.now(UTC) - parse_timestamp(state.timestamp)).total_seconds()
    assert 119.0 < age < 125.0
    assert state.header_id == 0


def test_state_rates_are_random_but_seeded() -> None:
    def pattern(seed: int) -> list[int]:
        vehicle = _vehicle(duplicate_states=0.5, seed=seed)
        return [len(vehicle.build_states()) for _ in range(40)]

    first = pattern(1)
    assert set(first) == {1, 2}
    assert 8 < first.count(2) < 32
    assert pattern(1) == first
    assert pattern(2) != first


def test_well_behaved_vehicle_publishes_one_state_each() -> None:
    vehicle = make_vehicle()
    assert [[s.header_id for s in vehicle.build_states()] for _ in range(3)] == [[0], [1], [2]]


# ---------------------------------------------------------------------------- timed episodes
def test_silence_starts_and_ends_on_the_simulated_clock(caplog: pytest.LogCaptureFixture) -> None:
    caplog.set_level(logging.INFO)
    vehicle = _vehicle(silent_at=2.0, silent_for=3.0)
    run(vehicle, 1.9)
    assert not vehicle.silent
    run(vehicle, 0.2)
    assert vehicle.silent
    run(vehicle, 2.7)
    assert vehicle.silent
    for _ in range(5):
        vehicle.take_state_due()
        vehicle.tick(0.1)
        if not vehicle.silent:
            break
    assert vehicle.sim_time == pytest.approx(5.0)
    assert vehicle.take_state_due()  # a fresh state right after the silence
    assert len(_fired(caplog, "silent")) == 2


def test_programmatic_silence_with_duration() -> None:
    vehicle = make_vehicle()
    vehicle.saboteur.silence(1.0)
    assert vehicle.silent
    run(vehicle, 1.1)
    assert not vehicle.silent


def test_disconnect_is_requested_once_at_its_time() -> None:
    vehicle = _vehicle(disconnect_at=1.0, disconnect_for=4.0)
    run(vehicle, 0.9)
    assert vehicle.saboteur.take_disconnect() is None
    run(vehicle, 0.2)
    assert vehicle.saboteur.take_disconnect() == 4.0
    run(vehicle, 5.0)
    assert vehicle.saboteur.take_disconnect() is None


def test_manual_mode_clears_the_order_and_refuses_orders_and_actions() -> None:
    vehicle = make_vehicle()
    pick = action("pick", "p1")
    vehicle.on_order(make_order("o1", ["n1", "n2", "n3"], actions={"n3": [pick]}))
    run(vehicle, 2.0)
    vehicle.misbehave(Misbehaviour(mode=OperatingMode.MANUAL, mode_at=0.5, mode_for=10.0))
    run(vehicle, 0.4)
    assert vehicle.operating_mode is OperatingMode.AUTOMATIC
    for _ in range(3):
        vehicle.tick(0.1)
        if vehicle.operating_mode is OperatingMode.MANUAL:
            break
    state = vehicle.build_state()  # the state of the very tick the mode changed
    assert state.operating_mode is OperatingMode.MANUAL
    assert (state.node_states, state.edge_states, state.driving) == ([], [], False)
    assert (state.order_id, state.last_node_id) == ("o1", "n1")  # ids are kept
    assert status(vehicle, "p1") is ActionStatus.FAILED
    x = vehicle.x
    run(vehicle, 2.0)
    assert vehicle.x == x
    assert not vehicle.on_order(make_order("o2", ["n1", "n2"]))
    assert error_types(vehicle) == ["orderError"]
    vehicle.on_instant_actions(instant(action("startPause", "sp"), action("stateRequest", "sr")))
    assert (status(vehicle, "sp"), status(vehicle, "sr")) == (
        ActionStatus.FAILED,
        ActionStatus.FINISHED,
    )
    assert not vehicle.paused
    run(vehicle, 8.0)
    assert vehicle.build_state().operating_mode is OperatingMode.AUTOMATIC
    # The cleared order cannot be updated; a new orderId from where it stands is fine.
    assert not vehicle.on_order(make_order("o1", ["n3"], update_id=1, first_seq=4))
    assert vehicle.on_order(make_order("o3", ["n1", "n2"], actions={}))


@pytest.mark.parametrize("mode", [OperatingMode.SERVICE, OperatingMode.TEACHIN])
def test_switching_mode_directly_stops_at_once(mode: OperatingMode) -> None:
    vehicle = make_vehicle()
    vehicle.on_order(make_order("o1", ["n1", "n2"]))
    run(vehicle, 1.0)
    vehicle.set_operating_mode(mode)
    state = vehicle.build_state()
    assert (state.operating_mode, state.driving, state.node_states) == (mode, False, [])
    vehicle.set_operating_mode(OperatingMode.AUTOMATIC)
    assert vehicle.on_order(make_order("o2", ["n1", "n2"]))


def test_semiautomatic_keeps_the_order() -> None:
    vehicle = make_vehicle()
    vehicle.on_order(make_order("o1", ["n1", "n2"]))
    vehicle.set_operating_mode(OperatingMode.SEMIAUTOMATIC)
    assert vehicle.build_state().operating_mode is OperatingMode.SEMIAUTOMATIC
    run_until(vehicle, finished)
    assert vehicle.last_node_id == "n2"


def test_mode_stays_without_duration_until_the_misbehaviour_is_replaced() -> None:
    vehicle = _vehicle(mode="SERVICE")
    run(vehicle, 100.0)
    assert vehicle.operating_mode is OperatingMode.SERVICE
    vehicle.misbehave(Misbehaviour())
    assert vehicle.operating_mode is OperatingMode.AUTOMATIC


# ---------------------------------------------------------------------------- actions and FATAL
def test_failing_action_type_reports_failed_and_an_error(caplog: pytest.LogCaptureFixture) -> None:
    caplog.set_level(logging.INFO)
    vehicle = _vehicle(fail_actions=("pick",), fail_count=1)
    picks = {"n2": [action("pick", "p1", loadId="A")], "n3": [action("pick", "p2", loadId="B")]}
    vehicle.on_order(make_order("o1", ["n1", "n2", "n3"], actions=picks))
    run_until(vehicle, lambda v: status(v, "p1") is ActionStatus.FAILED)
    state = vehicle.build_state()
    failed = [a for a in state.action_states if a.action_id == "p1"][0]
    assert failed.result_description
    assert [(e.error_type, e.error_level) for e in state.errors] == [
        ("actionFailed", ErrorLevel.WARNING)
    ]
    assert _refs(state) == {"actionId": "p1", "actionType": "pick"}
    assert vehicle.loads == []  # the failed pick had no effect
    run_until(vehicle, finished)
    assert status(vehicle, "p2") is ActionStatus.FINISHED  # budget of one used up
    assert [ld.load_id for ld in vehicle.loads] == ["B"]
    assert error_types(vehicle) == ["actionFailed"]  # kept until the next new order
    assert vehicle.on_order(make_order("o2", ["n3", "n4"]))
    assert error_types(vehicle) == []
    assert len(_fired(caplog, "fail_actions")) == 1


def test_failing_instant_action() -> None:
    vehicle = _vehicle(fail_actions=("startCharging",))
    vehicle.on_instant_actions(instant(action("startCharging", "c1")))
    assert status(vehicle, "c1") is ActionStatus.FAILED
    assert not vehicle.charging


def test_fatal_error_while_driving_after_n_nodes(caplog: pytest.LogCaptureFixture) -> None:
    caplog.set_level(logging.INFO)
    vehicle = _vehicle(fatal_after_nodes=2, fatal_error="motorFault")
    vehicle.on_order(make_order("o1", ["n1", "n2", "n3"]))
    states = run(vehicle, 8.0)
    assert vehicle.last_node_id == "n2"
    assert 5.0 < vehicle.x < 5.2  # stopped on the edge right after n2
    state = vehicle.build_state()
    assert not state.driving
    assert [(e.error_type, e.error_level) for e in state.errors] == [
        ("motorFault", ErrorLevel.FATAL)
    ]
    assert [n.node_id for n in state.node_states] == ["n3"]  # the order is kept
    assert any(s.errors for s in states)
    assert len(_fired(caplog, "fatal_after_nodes")) == 1
    vehicle.clear_injected_errors()
    run_until(vehicle, finished)
    assert vehicle.last_node_id == "n3"
    assert error_types(vehicle) == []  # fires once only


def test_replacing_the_misbehaviour_keeps_deferred_orders() -> None:
    vehicle = _vehicle(delay_orders=2.0)
    vehicle.on_order(make_order("o1", ["n1", "n2"]))
    vehicle.misbehave(Misbehaviour())
    run(vehicle, 2.1)
    assert vehicle.order_id == "o1"


@pytest.mark.parametrize(
    "settings",
    [
        {"duplicate_states": 1.5},
        {"reorder_states": -0.1},
        {"delay_orders": -1.0},
        {"silent_for": float("inf")},
        {"reject_count": -1},
        {"reject_orders": ""},
        {"mode": "FLYING"},
        {"mode_for": -2.0},
    ],
)
def test_invalid_misbehaviour_is_refused(settings: dict[str, object]) -> None:
    with pytest.raises(ValueError, match=next(iter(settings))):
        Misbehaviour(**settings)  # type: ignore[arg-type]


def test_default_misbehaviour_is_inactive() -> None:
    assert not Misbehaviour().active
    assert not Misbehaviour(seed=3).active
    assert Misbehaviour(drop_orders=1).active
