"""Which messages put a vehicle in the next live broadcast: an idle vehicle repeating its
state (new header id and timestamp, its battery draining below what the page shows) or its
pose is left out; anything the page shows that changed, and any vehicle with an order, is in."""

from datetime import UTC, datetime, timedelta
from types import SimpleNamespace

import msgspec
import pytest

import vda5050
from control.controller import Controller
from control.live import LiveVehicle, shows_change
from control.snapshots import live_row
from tests.control.fakes import FakeStore, state, topic

NOW = datetime(2026, 1, 1, tzinfo=UTC)


def _state(**fields: object) -> vda5050.State:
    base = vda5050.decode(vda5050.TopicKind.STATE, state(header_id=1))
    return msgspec.structs.replace(base, **fields)


def _battery(charge: float, charging: bool = False) -> vda5050.BatteryState:
    return vda5050.BatteryState(battery_charge=charge, charging=charging)


def _broadcast(vehicle: LiveVehicle) -> None:
    """What a broadcast does to a vehicle in it: its row built, its mark taken."""
    live_row(vehicle, {})
    vehicle.needs_broadcast = False


def _idle(first: vda5050.State) -> LiveVehicle:
    vehicle = LiveVehicle("sim", "AGV-1", "uagv")
    vehicle.apply_state(first, received_at=NOW)
    assert vehicle.needs_broadcast  # a first state always
    _broadcast(vehicle)
    return vehicle


def test_the_same_state_again_shows_no_change() -> None:
    before = _state(battery_state=_battery(80.04))
    again = _state(header_id=2, timestamp="2026-01-01T00:00:00.50Z", battery_state=_battery(80.01))
    assert not shows_change(before, again)
    vehicle = _idle(before)
    vehicle.apply_state(again, received_at=NOW + timedelta(seconds=0.5))
    assert vehicle.needs_flush
    assert not vehicle.needs_broadcast


@pytest.mark.parametrize(
    "change",
    [
        {"battery_state": _battery(79.9)},  # shown to 0.1 %
        {"battery_state": _battery(80.0, charging=True)},
        {"driving": True},
        {"last_node_id": "b"},
        {"operating_mode": vda5050.OperatingMode("MANUAL")},
        {"paused": True},
        {"errors": [vda5050.Error(error_type="x", error_level=vda5050.ErrorLevel("WARNING"))]},
        {
            "agv_position": vda5050.AgvPosition(
                x=1.0, y=2.0, theta=0.0, map_id="m", position_initialized=True
            )
        },
        {"node_states": [vda5050.NodeState(node_id="b", sequence_id=2, released=True)]},
    ],
)
def test_a_change_the_page_shows_puts_the_vehicle_in_the_next_broadcast(
    change: dict[str, object],
) -> None:
    before = _state(battery_state=_battery(80.0))
    after = _state(header_id=2, **{"battery_state": _battery(80.0), **change})
    assert shows_change(before, after)
    vehicle = _idle(before)
    vehicle.apply_state(after, received_at=NOW)
    assert vehicle.needs_broadcast


def test_a_vehicle_with_an_order_is_in_every_broadcast() -> None:
    controller = Controller(store=FakeStore(), interface_name="uagv")
    controller.load()
    controller.handle_message(topic(), state(header_id=1, order_id="o-1", nodes=("b",)))
    vehicle = controller.fleet.by_pk(1)
    assert vehicle is not None
    vehicle.execution = SimpleNamespace(transport_order_id=7)  # type: ignore[assignment]
    _broadcast(vehicle)
    controller.handle_message(topic(), state(header_id=2, order_id="o-1", nodes=("b",)))
    assert vehicle.needs_broadcast


def test_a_clock_skew_that_moved_a_tenth_of_a_second_is_shown_again() -> None:
    first = _state(timestamp="2026-01-01T00:00:00.00Z")
    vehicle = _idle(first)
    later = NOW + timedelta(seconds=1)
    vehicle.apply_state(_state(header_id=2, timestamp="2026-01-01T00:00:01.05Z"), received_at=later)
    assert not vehicle.needs_broadcast  # 50 ms of jitter
    vehicle.apply_state(_state(header_id=3, timestamp="2026-01-01T00:00:01.20Z"), received_at=later)
    assert vehicle.needs_broadcast  # 200 ms


def test_a_pose_is_broadcast_only_when_it_moved() -> None:
    pose = vda5050.AgvPosition(x=1.0, y=2.0, theta=0.0, map_id="m", position_initialized=True)
    vehicle = _idle(_state(agv_position=pose))
    vehicle.apply_pose(msgspec.structs.replace(pose))
    assert not vehicle.needs_broadcast
    vehicle.apply_pose(msgspec.structs.replace(pose, x=1.01))
    assert vehicle.needs_broadcast
