"""control's liveness probe end to end in the controller: a vehicle silent for PROBE_AFTER gets
one stateRequest from the periodic pass and turns UNREACHABLE if no state comes within the
grace; one that answers stays ONLINE. Real clock, short times (the defaults are 10 s and 5 s)."""

import json
import time
from collections.abc import Iterator
from typing import Any

import pytest

from control.controller import Controller
from control.live import LiveVehicle
from tests.control.fakes import FakeStore, state, topic

AFTER = 0.4  # s of silence before the probe
GRACE = 0.8  # s to answer it


class Sent(list[tuple[str, dict[str, Any]]]):
    def __call__(self, topic: str, payload: bytes, qos: int) -> None:
        self.append((topic, json.loads(payload)))

    def state_requests(self) -> int:
        return sum(
            a["actionType"] == "stateRequest"
            for t, m in self
            if t.endswith("/instantActions")
            for a in m["actions"]
        )


@pytest.fixture
def sent() -> Sent:
    return Sent()


@pytest.fixture
def controller(sent: Sent) -> Iterator[Controller]:
    ctrl = Controller(
        store=FakeStore(),
        interface_name="uagv",
        publish=sent,
        liveness_probe_after=AFTER,
        liveness_probe_grace=GRACE,
    )
    ctrl.load()
    yield ctrl
    assert ctrl.counters["handler_errors"] == 0


def _vehicle(controller: Controller) -> LiveVehicle:
    vehicle = controller.fleet.by_pk(1)
    assert vehicle is not None
    return vehicle


def _passes_until(controller: Controller, deadline: float) -> None:
    """The control loop's periodic per-vehicle pass, about every 50 ms until `deadline`."""
    while time.monotonic() < deadline:
        controller.collect_flush()
        time.sleep(0.05)


def test_a_silent_vehicle_gets_one_state_request_then_turns_unreachable(
    controller: Controller, sent: Sent
) -> None:
    controller.handle_message(topic(), state(header_id=1))  # declares no interval: 30 s
    last_state = time.monotonic()

    _passes_until(controller, last_state + AFTER - 0.1)
    assert sent.state_requests() == 0  # not silent long enough yet
    _passes_until(controller, last_state + AFTER + 0.2)
    assert sent.state_requests() == 1
    assert _vehicle(controller).connection == "ONLINE"  # a question, not a verdict

    _passes_until(controller, last_state + AFTER + GRACE + 0.4)

    assert sent.state_requests() == 1  # one per silence episode
    assert controller.counters["liveness_probes"] == 1
    assert _vehicle(controller).connection == "UNREACHABLE"
    assert _vehicle(controller).last_link.value == "UNREACHABLE"  # flushed as such


def test_a_vehicle_that_answers_the_probe_stays_online(controller: Controller, sent: Sent) -> None:
    controller.handle_message(topic(), state(header_id=1))
    deadline = time.monotonic() + 2 * (AFTER + GRACE)
    answered = 0
    while time.monotonic() < deadline:
        controller.collect_flush()
        if sent.state_requests() > answered:  # the vehicle answers each stateRequest at once
            answered += 1
            controller.handle_message(topic(), state(header_id=1 + answered))
        assert _vehicle(controller).connection == "ONLINE"
        time.sleep(0.05)

    assert answered >= 2  # silent again after each answer: probed again, never unreachable
    assert controller.counters["liveness_probes"] == answered


def test_no_probe_when_it_is_off(sent: Sent) -> None:
    controller = Controller(
        store=FakeStore(), interface_name="uagv", publish=sent, liveness_probe_after=0
    )
    controller.load()
    controller.handle_message(topic(), state(header_id=1))

    _passes_until(controller, time.monotonic() + AFTER + 0.3)

    assert sent.state_requests() == 0
    assert _vehicle(controller).connection == "ONLINE"
