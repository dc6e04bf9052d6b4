"""control's live rows: rebuilt only where their inputs changed, yet always equal to the row
built from scratch; and none at all while no browser has the live page open."""

import copy
import json
import time
from collections.abc import Callable
from typing import Any

import vda5050
from control.controller import Controller
from control.execution import LayoutIndex, NodePlace
from control.live import InstantActionTrack, LiveVehicle
from control.snapshots import LiveDeltas, browser_row, live_row
from tests.control import fakes
from tests.control.fakes import FakeStore, state, topic
from tests.control.test_traffic_controller import World


def _controller() -> Controller:
    controller = Controller(store=FakeStore(), interface_name="uagv")
    controller.load()
    controller.live_page_open = lambda: True
    return controller


def _vehicle(controller: Controller) -> LiveVehicle:
    vehicle = controller.fleet.by_pk(1)
    assert vehicle is not None
    return vehicle


def _connection(header_id: int, connection_state: str) -> bytes:
    message = {
        "headerId": header_id,
        "timestamp": "2026-01-01T00:00:00.00Z",
        "version": fakes.PROTOCOL["version"],
        "manufacturer": "sim",
        "serialNumber": "AGV-1",
        "connectionState": connection_state,
    }
    return json.dumps(message).encode()


def _moved(vehicle: LiveVehicle, x: float) -> None:
    """A visualization message: a new pose, nothing else."""
    vehicle.visual_position = vda5050.AgvPosition(
        x=x, y=0.5, theta=1.0, map_id="demo", position_initialized=True
    )


def test_live_rows_equal_rows_built_from_scratch_through_every_kind_of_change() -> None:
    controller = _controller()
    vehicle = _vehicle(controller)
    send = controller.handle_message
    changes: list[Callable[[], object]] = [
        lambda: send(topic(), state(header_id=1, driving=True, nodes=("b", "c"), horizon=("d",))),
        lambda: send(topic(), state(header_id=2, driving=True, nodes=("b", "c"), horizon=("d",))),
        lambda: _moved(vehicle, 0.4),
        lambda: send(topic(), state(header_id=3, last_node="b", nodes=("c",), horizon=("d",))),
        lambda: setattr(vehicle, "factsheet", {"physicalParameters": {"length": 2, "width": 1}}),
        lambda: send(topic(), state(header_id=4, errors=(("blocked", "FATAL", "TO-7"),))),
        lambda: vehicle.track(InstantActionTrack("ia-1", "cancelOrder", "SENT")),
        lambda: send(topic(kind="connection"), _connection(5, "OFFLINE")),
        lambda: send(topic(kind="connection"), _connection(6, "ONLINE")),
        lambda: send(topic(), state(header_id=7, last_node="c", nodes=("d",))),
        lambda: setattr(controller, "layouts", {"demo": _shifted(fakes.LINE, 10.0)}),
        lambda: send(topic(), state(header_id=8, last_node="d")),
    ]
    seen = []

    for change in changes:
        change()
        row = live_row(vehicle, controller.layouts, controller.traffic)

        assert row == browser_row(vehicle, controller.layouts, controller.traffic)
        seen.append(row)
    statuses = [row["status"] for row in seen]
    assert {"driving", "error", "offline", "idle"} <= set(statuses)
    assert seen[-2]["base"] == [[13.0, 0.0]]  # d on the reloaded (shifted) layout


def _shifted(layout: LayoutIndex, dx: float) -> LayoutIndex:
    nodes = {n: NodePlace(p.x + dx, p.y, p.theta, p.map_id) for n, p in layout.nodes.items()}
    return LayoutIndex(layout.map_id, nodes, dict(layout.edges))


def test_a_vehicle_that_only_moved_reuses_its_route_and_footprint() -> None:
    controller = _controller()
    vehicle = _vehicle(controller)
    controller.handle_message(topic(), state(header_id=1, driving=True, nodes=("b", "c")))
    first = live_row(vehicle, controller.layouts)

    controller.handle_message(topic(), state(header_id=2, driving=True, nodes=("b", "c")))
    _moved(vehicle, 0.7)
    second = live_row(vehicle, controller.layouts)

    assert (first["x"], second["x"]) == (0.0, 0.7)
    assert second["base"] is first["base"]
    assert second["size"] is first["size"]


def test_the_route_is_rebuilt_once_the_vehicle_passed_a_node() -> None:
    controller = _controller()
    vehicle = _vehicle(controller)
    controller.handle_message(topic(), state(header_id=1, driving=True, nodes=("b", "c")))
    first = live_row(vehicle, controller.layouts)

    controller.handle_message(topic(), state(header_id=2, last_node="b", nodes=("c",)))
    second = live_row(vehicle, controller.layouts)

    assert (first["base"], second["base"]) == ([[1.0, 0.0], [2.0, 0.0]], [[2.0, 0.0]])


def test_a_row_handed_out_is_never_changed_by_later_rows() -> None:
    controller = _controller()
    vehicle = _vehicle(controller)
    controller.handle_message(topic(), state(header_id=1, driving=True, nodes=("b",)))
    row = live_row(vehicle, controller.layouts)
    kept = copy.deepcopy(row)

    controller.handle_message(
        topic(), state(header_id=2, last_node="b", errors=(("e", "WARNING", "x"),))
    )
    _moved(vehicle, 3.0)
    live_row(vehicle, controller.layouts)

    assert row == kept


def test_no_rows_are_built_while_no_page_is_open_and_none_are_lost() -> None:
    controller = _controller()
    controller.handle_message(topic(), state(header_id=1))
    watched = False
    controller.live_page_open = lambda: watched

    assert controller.collect_broadcast() == []
    assert _vehicle(controller).needs_broadcast

    watched = True
    rows = controller.collect_broadcast()

    assert [row["serial"] for row in rows] == ["AGV-1"]
    assert not _vehicle(controller).needs_broadcast
    assert controller.collect_broadcast() == []  # nothing changed since


def test_the_first_broadcast_after_a_pause_sends_whole_rows() -> None:
    deltas = LiveDeltas(keyframe_every=10, pause_s=0.01)
    row: dict[str, Any] = {"id": 7, "manufacturer": "Acme", "serial": "AGV-1", "x": 1.0}
    deltas.payload([row])
    time.sleep(0.05)  # nobody watched, or nothing changed

    again = deltas.payload([row | {"x": 2.0}])

    assert again == {"vehicles": [row | {"x": 2.0}], "changes": []}


def test_broadcasts_without_a_pause_send_only_changes() -> None:
    deltas = LiveDeltas(keyframe_every=10, pause_s=60.0)
    row: dict[str, Any] = {"id": 7, "manufacturer": "Acme", "serial": "AGV-1", "x": 1.0}
    deltas.payload([row])

    again = deltas.payload([row | {"x": 2.0}])

    assert again == {"vehicles": [], "changes": [{"id": 7, "x": 2.0}]}


def test_live_rows_follow_traffic_through_a_crossing() -> None:
    world = World(["AGV-1", "AGV-2"], traffic=True)
    controller = world.controller
    vehicles = list(controller.fleet.vehicles.values())
    reservations = set()

    for _ in range(40):
        world.run(0.5)
        for vehicle in vehicles:
            row = live_row(vehicle, controller.layouts, controller.traffic)

            assert row == browser_row(vehicle, controller.layouts, controller.traffic)
            reservations.add(json.dumps(row["reserved"]))
    assert len(reservations) >= 3  # reserved nodes came and went as the vehicles drove
