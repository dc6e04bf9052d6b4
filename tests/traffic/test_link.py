"""The traffic link of `control`, pure: a fake layout, live vehicles fed with built states."""

import time
from datetime import UTC, datetime

import msgspec
import pytest

import vda5050
from control.execution import LayoutIndex, NodePlace, OrderExecution, Window
from control.live import LiveVehicle
from control.session import Link
from control.traffic_link import TrafficLink
from control.traffic_support import (
    DEFAULT_CLASS,
    envelope,
    layout_of,
    vehicle_class,
    window,
)
from traffic import VehicleClass


def plus(spacing: float = 2.0) -> LayoutIndex:
    """A crossing: W2 W1 C E1 E2 across, N2 N1 C S1 S2 down, two-way edges, `spacing` apart."""
    arms = {"W": (-1, 0), "E": (1, 0), "N": (0, 1), "S": (0, -1)}
    nodes = {"C": NodePlace(0.0, 0.0, None, "m")}
    edges = {}
    for arm, (dx, dy) in arms.items():
        previous = "C"
        for i in (1, 2):
            node = f"{arm}{i}"
            nodes[node] = NodePlace(dx * i * spacing, dy * i * spacing, None, "m")
            edges[(previous, node)] = f"{previous}{node}"
            edges[(node, previous)] = f"{node}{previous}"
            previous = node
    return LayoutIndex("m", nodes, edges)


LAYOUTS = {"m": plus()}


def state(
    serial: str,
    node: str,
    *,
    order_id: str = "",
    seq: int = 0,
    pending: tuple[str, ...] = (),
    mode: str = "AUTOMATIC",
    fatal: bool = False,
) -> vda5050.State:
    return vda5050.State(
        header_id=1,
        timestamp="2026-01-01T00:00:00.00Z",
        version="2.0.0",
        manufacturer="sim",
        serial_number=serial,
        order_id=order_id,
        order_update_id=0,
        last_node_id=node,
        last_node_sequence_id=seq,
        driving=False,
        operating_mode=vda5050.OperatingMode(mode),
        node_states=[
            vda5050.NodeState(node_id=n, sequence_id=seq + 2 * (i + 1), released=True)
            for i, n in enumerate(pending)
        ],
        edge_states=[],
        action_states=[],
        battery_state=vda5050.BatteryState(battery_charge=80.0, charging=False),
        errors=[vda5050.Error(error_type="bumper", error_level=vda5050.ErrorLevel.FATAL)]
        if fatal
        else [],
        safety_state=vda5050.SafetyState(e_stop=vda5050.EStop.NONE, field_violation=False),
        agv_position=vda5050.AgvPosition(
            x=0.0, y=0.0, theta=0.0, map_id="m", position_initialized=True
        ),
    )


class Rig:
    """A link with live vehicles; `report` applies a state like the controller does."""

    def __init__(self, *starts: tuple[str, str]) -> None:
        self.vehicles = {s: LiveVehicle("sim", s, "uagv") for s, _ in starts}
        self.link = TrafficLink(lambda: self.vehicles.values())
        self.link.ensure(LAYOUTS)
        for serial, node in starts:
            self.report(serial, state(serial, node))

    def report(self, serial: str, message: vda5050.State) -> list[str]:
        vehicle = self.vehicles[serial]
        vehicle.apply_state(message, received_at=datetime.now(UTC))
        others = self.link.observe(vehicle, message, time.monotonic())
        return [o.serial_number for o in others]

    def start(self, serial: str, route: list[str], pickup: str) -> tuple[OrderExecution, Window]:
        execution = OrderExecution.plan(
            transport_order_id=1, vda_order_id=f"O-{serial}", route=route, pickup=pickup
        )
        first = self.link.first_window(self.vehicles[serial], execution, "m", None)
        assert first is not None
        execution.sent(0, first)
        self.vehicles[serial].execution = execution
        return execution, first


def test_vehicle_class_comes_from_the_factsheet_or_the_default() -> None:
    camel = {"physicalParameters": {"length": 1.5, "width": 0.9, "speedMax": 2.0}}
    snake = {"physical_parameters": {"length": 1.0, "width": 0.6}}
    assert vehicle_class(camel) == VehicleClass("factsheet", length=1.5, width=0.9, speed=2.0)
    assert vehicle_class(snake) == VehicleClass("factsheet", length=1.0, width=0.6, speed=1.0)
    assert vehicle_class(None) is DEFAULT_CLASS
    assert vehicle_class({"physicalParameters": {"length": -1, "width": 1}}) is DEFAULT_CLASS
    both = envelope([vehicle_class(camel), vehicle_class(snake)])
    assert (both.length, both.width, both.speed) == (1.5, 0.9, 1.0)


def test_layout_takes_lengths_from_positions_and_speed_limits_from_zones() -> None:
    index = LayoutIndex(
        "m",
        {
            "a": NodePlace(0.0, 0.0, None, "m"),
            "b": NodePlace(3.0, 4.0, None, "m"),
            "c": NodePlace(3.0, 4.0, None, "m"),  # same place as b: that edge is skipped
        },
        {("a", "b"): "ab", ("b", "c"): "bc"},
        speed_limits={"ab": 0.5},
    )
    layout = layout_of(index)
    assert [(e.length, e.max_speed) for e in layout.edges] == [(5.0, 0.5)]


@pytest.mark.parametrize(
    ("first", "base_end", "max_nodes", "expected"),
    [
        (0, 3, None, Window(0, 6, 3)),
        (0, 6, 4, Window(0, 3, 3)),
        (2, 1, None, Window(2, 6, 2)),  # never below the stitching node
    ],
)
def test_window_is_capped_by_the_message_size_and_the_released_base(
    first, base_end, max_nodes, expected
) -> None:
    assert window(7, first, base_end, max_nodes) == expected


def test_a_lone_vehicle_gets_its_route_planned_through_pickup_and_drop() -> None:
    rig = Rig(("A", "W2"))
    execution, first = rig.start("A", ["W2", "W1", "C", "E1", "E2"], "W1")

    assert execution.route == ["W2", "W1", "C", "E1", "E2"]
    assert execution.pick_index == 1
    assert (first.first, first.last) == (0, 4)
    assert first.released == 4  # nobody else around: as far as the policy allows
    assert rig.link.controls(rig.vehicles["A"], "O-A")
    assert rig.link.stats.decisions == 1


def test_crossing_vehicle_waits_and_is_released_when_the_first_passed() -> None:
    rig = Rig(("A", "W2"), ("B", "N2"))
    a, first_a = rig.start("A", ["W2", "W1", "C", "E1", "E2"], "W1")
    b, first_b = rig.start("B", ["N2", "N1", "C", "S1", "S2"], "N1")

    assert first_a.released == 4
    assert first_b.released == 1  # up to N1; the crossing C is A's first
    rig.report("B", state("B", "N1", order_id="O-B", seq=2))  # at its decision point
    assert rig.link.waiting_for(rig.vehicles["B"]) == ["A"]
    assert rig.link.next_window(rig.vehicles["B"], b, None) is None

    assert rig.report("A", state("A", "C", order_id="O-A", seq=4, pending=("E1", "E2"))) == []
    woken = rig.report("A", state("A", "E1", order_id="O-A", seq=6, pending=("E2",)))

    assert woken == ["B"]
    extension = rig.link.next_window(rig.vehicles["B"], b, None)
    assert extension is not None
    assert (extension.first, extension.released) == (first_b.released, 4)
    assert rig.link.waiting_for(rig.vehicles["B"]) == []


def test_vehicle_in_error_is_a_static_obstacle_until_it_recovers() -> None:
    rig = Rig(("A", "C"), ("B", "W2"))
    rig.report("A", state("A", "C", fatal=True))

    assert rig.link.tracked["sim/A"].static == "fatal error"
    assert (
        rig.link.first_window(
            rig.vehicles["B"],
            OrderExecution.plan(
                transport_order_id=2, vda_order_id="O-B", route=["W2", "W1", "C", "E1"], pickup="W1"
            ),
            "m",
            None,
        )
        is None
    )  # the only way east is through the broken vehicle

    rig.report("A", state("A", "N1"))  # repaired and moved by hand

    assert rig.link.tracked["sim/A"].static is None
    _, first = rig.start("B", ["W2", "W1", "C", "E1"], "W1")
    assert first.released == 3


@pytest.mark.parametrize("mode", ["MANUAL", "SERVICE"])
def test_manual_modes_block_and_automatic_restores(mode: str) -> None:
    rig = Rig(("A", "E1"))
    rig.report("A", state("A", "E1", mode=mode))
    assert rig.link.tracked["sim/A"].static == f"{mode} mode"
    rig.report("A", state("A", "E2"))
    assert rig.link.tracked["sim/A"].static is None
    _, first = rig.start("A", ["E2", "E1", "C"], "E1")
    assert first.released == 2


def test_offline_vehicle_is_blocked_by_tick() -> None:
    rig = Rig(("A", "E1"))
    rig.link.tick(time.monotonic() + 3600)  # an hour without a state
    assert rig.link.tracked["sim/A"].static == "offline"


def test_an_order_that_ends_mid_route_frees_the_rest() -> None:
    rig = Rig(("A", "W2"), ("B", "N2"))
    a, _ = rig.start("A", ["W2", "W1", "C", "E1", "E2"], "W1")
    rig.report("A", state("A", "W1", order_id="O-A", seq=2, pending=("C", "E1", "E2")))
    rig.report("A", state("A", "W1"))  # cancelled at W1: the vehicle cleared its order
    rig.link.ended(rig.vehicles["A"], time.monotonic())

    _, first_b = rig.start("B", ["N2", "N1", "C", "S1", "S2"], "N1")
    assert first_b.released == 4  # nothing of A's old route holds the crossing


def test_a_vehicle_on_a_reserved_node_is_not_placed_and_gets_no_plan() -> None:
    rig = Rig(("A", "C"), ("B", "C"))
    assert "sim/B" not in rig.link.tracked
    assert any("cannot place sim/B" in p for p in rig.link.problems)


def test_a_vehicle_driving_an_order_traffic_did_not_plan_is_an_obstacle() -> None:
    rig = Rig(("A", "W1"))
    rig.report("A", state("A", "W1", order_id="adopted", pending=("C",)))
    assert rig.link.tracked["sim/A"].static == "driving an order traffic did not plan"


def test_an_order_that_went_offline_is_planned_again_at_its_decision_point() -> None:
    rig = Rig(("A", "W2"), ("B", "N2"))
    rig.start("B", ["N2", "N1", "C", "S1", "S2"], "N1")
    a, first = rig.start("A", ["W2", "W1", "C", "E1", "E2"], "W1")
    assert first.released == 1  # B crosses first
    rig.vehicles["A"].session.last_alive_at = -1e9  # silent for ages
    rig.link.tick(time.monotonic())

    assert rig.link.tracked["sim/A"].static == "offline"
    assert rig.link.lost(rig.vehicles["A"], "O-A")
    assert rig.link.tracked["sim/B"].static is None

    # Back, still driving its released base: no re-plan yet, nothing more released.
    rig.report("A", state("A", "W2", order_id="O-A", seq=0, pending=("W1",)))
    assert rig.link.lost(rig.vehicles["A"], "O-A")
    # At its decision point: planned again from W1, behind B.
    rig.report("A", state("A", "W1", order_id="O-A", seq=2))
    assert rig.link.controls(rig.vehicles["A"], "O-A")
    assert rig.link.tracked["sim/A"].offset == 1
    assert rig.link.next_window(rig.vehicles["A"], a, None) is None

    rig.report("B", state("B", "C", order_id="O-B", seq=4, pending=("S1", "S2")))
    woken = rig.report("B", state("B", "S1", order_id="O-B", seq=6, pending=("S2",)))
    assert woken == ["A"]
    extension = rig.link.next_window(rig.vehicles["A"], a, None)
    assert extension == Window(1, 4, 4)
    assert a.route == ["W2", "W1", "C", "E1", "E2"]
    # Progress on the re-adopted order counts with the offset: E1 is route index 3.
    rig.report("A", state("A", "E1", order_id="O-A", seq=6, pending=("E2",)))
    assert rig.link.managers["m"].vehicle("sim/A").passed == 2


def test_vehicles_offline_at_once_are_all_blocked_before_those_behind_are_re_planned(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    rig = Rig(("A", "W2"), ("B", "N2"), ("C", "S2"))
    rig.start("A", ["W2", "W1", "C", "E1", "E2"], "W1")
    rig.start("B", ["N2", "N1", "C", "E1"], "N1")
    rig.start("C", ["S2", "S1", "C", "W1"], "S1")  # behind A and B at the crossing
    manager = rig.link.managers["m"]
    replanned: list[str] = []
    replan = manager.replan

    def counting(vehicle_id: str, now: float) -> object:
        replanned.append(vehicle_id)
        return replan(vehicle_id, now)

    monkeypatch.setattr(manager, "replan", counting)
    for serial in ("A", "B"):  # e.g. their connection dropped with the broker
        monkeypatch.setattr(rig.vehicles[serial].session, "link", lambda now: Link.OFFLINE)
    rig.link.tick(time.monotonic())

    assert [rig.link.tracked[f"sim/{s}"].static for s in "ABC"] == ["offline", "offline", None]
    assert replanned.count("sim/C") == 1  # once, after both blocks, not once per block
    assert not {"sim/A", "sim/B"} & set(replanned)


def test_the_previous_order_s_sequence_id_is_not_progress_on_a_round_trip() -> None:
    # A vehicle keeps the old order's lastNodeSequenceId until it passes the new first node;
    # on a round trip the new route passes the same node at that index again (found in a load
    # run: orders home -> pick -> drop -> home, read as finished at once, beyond the base).
    rig = Rig(("A", "W2"))
    rig.start("A", ["W2", "W1", "C"], "W1")
    rig.report("A", state("A", "W1", order_id="O-A", seq=2, pending=("C",)))
    rig.report("A", state("A", "C", order_id="O-A", seq=4))
    rig.link.ended(rig.vehicles["A"], time.monotonic())
    back = OrderExecution.plan(
        transport_order_id=2, vda_order_id="O-A2", route=["C", "E1", "C"], pickup="E1"
    )
    assert rig.link.first_window(rig.vehicles["A"], back, "m", None) is not None
    manager = rig.link.managers["m"]
    assert manager.vehicle("sim/A").route[2] == manager.layout.index["C"]

    # taken, standing on C: still the old sequence id 4, every node of the new order listed
    taken = msgspec.structs.replace(
        state("A", "C", order_id="O-A2", seq=4),
        node_states=[
            vda5050.NodeState(node_id=n, sequence_id=2 * i, released=i == 0)
            for i, n in enumerate(["C", "E1", "C"])
        ],
    )
    rig.report("A", taken)

    assert manager.vehicle("sim/A").passed == 0
    assert rig.link.problems == {}


def test_a_stalled_vehicle_is_counted_and_logged_once_with_its_trail(
    caplog: pytest.LogCaptureFixture,
) -> None:
    rig = Rig(("A", "W2"))
    rig.start("A", ["W2", "W1", "C", "E1", "E2"], "W1")  # then no state comes for minutes
    later = time.monotonic() + 120.0

    with caplog.at_level("WARNING", logger="control.traffic_link"):
        assert rig.link.safety(later) == {"cycles": 0, "stalled": 1}
        assert rig.link.safety(later + 2.0) == {"cycles": 0, "stalled": 1}

    lines = [r.getMessage() for r in caplog.records if "stalled" in r.getMessage()]
    assert len(lines) == 1  # once per stall, not at every look
    assert "sim/A stalled: passed 0, base 4 of 5 nodes" in lines[0]
    assert "started O-A: plan" in lines[0]


def test_a_vehicle_idle_for_minutes_is_not_stalled_when_its_next_order_starts() -> None:
    rig = Rig(("A", "W2"), ("B", "N2"))
    manager = rig.link.managers["m"]
    for name in ("sim/A", "sim/B"):
        manager.vehicle(name).last_progress -= 300.0  # both stood idle for five minutes
    rig.start("A", ["W2", "W1", "C", "E1", "E2"], "W1")
    rig.start("B", ["N2", "N1", "C", "S1", "S2"], "N1")  # waits for A at N1

    assert rig.link.safety(time.monotonic() + 30.0) == {"cycles": 0, "stalled": 0}
    assert rig.link.safety(time.monotonic() + 90.0)["stalled"] == 2  # nobody moved since
