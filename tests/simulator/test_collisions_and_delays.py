"""The simulator's own checks: footprint collisions between vehicles, and delay injection."""

import json
import math

import pytest

from simulator.__main__ import build_parser
from simulator.collisions import Body, CollisionChecker, Footprint, overlap
from simulator.config import StartPose, VehicleConfig
from simulator.delays import DelayConfig, DelayInjector, parse_range
from simulator.fleet import FleetConfig, build_vehicles, footprint_of
from simulator.layout import Layout, LayoutNode
from simulator.vehicle import VirtualVehicle
from tests.simulator.builders import make_order, make_vehicle

CAR = Footprint(1.2, 0.8)


def body(name: str, x: float, y: float, theta: float = 0.0) -> Body:
    return Body(name, x, y, theta, CAR)


@pytest.mark.parametrize(
    ("second", "expected"),
    [
        (body("b", 1.19, 0.0), True),  # nose into tail
        (body("b", 1.2, 0.0), False),  # touching is not overlapping
        (body("b", 0.0, 0.81), False),  # side by side with a gap
        (body("b", 0.0, 0.79), True),
        (body("b", 0.95, 0.95, math.pi / 4), False),  # turned, clear of the corner
        (body("b", 0.9, 0.7, math.pi / 4), True),  # turned into the corner
    ],
)
def test_overlap_of_rotated_rectangles(second: Body, expected: bool) -> None:
    assert overlap(body("a", 0.0, 0.0), second) is expected


def test_a_contact_is_counted_once_until_the_vehicles_separate() -> None:
    checker = CollisionChecker()
    apart = [body("A", 0.0, 0.0), body("B", 3.0, 0.0), body("C", 30.0, 30.0)]
    touching = [body("A", 0.0, 0.0), body("B", 1.0, 0.0), body("C", 30.0, 30.0)]

    assert checker.check(apart, 0.0) == []
    assert [(c.first, c.second) for c in checker.check(touching, 0.1)] == [("A", "B")]
    assert checker.check(touching, 0.2) == []  # the same contact
    checker.check(apart, 0.3)
    checker.check(touching, 0.4)  # a new contact

    assert checker.count == 2
    assert checker.steps == 5
    summary = checker.summary()
    assert summary["collisions"] == 2
    assert json.dumps(summary)  # what --summary writes


def test_pairs_across_grid_cells_are_checked() -> None:
    checker = CollisionChecker()
    # 2.88 m cells (twice the radius): these two straddle a cell border diagonally.
    found = checker.check([body("A", 2.8, 2.8), body("B", 3.0, 3.0)], 0.0)
    assert len(found) == 1


def test_footprint_comes_from_the_vehicle_factsheet() -> None:
    vehicle = VirtualVehicle(VehicleConfig(), StartPose("m", "n", 0.0, 0.0))
    physical = vehicle.build_factsheet().physical_parameters
    assert footprint_of(vehicle) == Footprint(physical.length, physical.width)


def test_delay_injection_holds_a_share_of_moves_for_a_time_in_range() -> None:
    injector = DelayInjector(DelayConfig(share=0.5, low=5.0, high=30.0, seed=4))
    held = 0
    for move in range(200):
        if injector.holds(move, 0.0):
            held += 1
            assert injector.holds(move, 4.99)  # at least `low`
            assert not injector.holds(move, 30.0)  # at most `high`
    assert held == injector.injected
    assert 70 < held < 130
    assert 5.0 * held <= injector.delayed_seconds <= 30.0 * held


def test_without_a_share_nothing_is_delayed() -> None:
    injector = DelayInjector(DelayConfig())
    assert not any(injector.holds(move, 0.0) for move in range(100))


def test_a_delayed_vehicle_starts_its_move_late() -> None:
    vehicle = make_vehicle("n1")
    vehicle.delays = DelayInjector(DelayConfig(share=1.0, low=3.0, high=3.0))
    assert vehicle.on_order(make_order("O-1", ["n1", "n2"]))
    for _ in range(25):  # 2.5 s: still held
        vehicle.tick(0.1)
    assert (vehicle.x, vehicle.driving) == (0.0, False)
    for _ in range(90):  # the rest of the delay, then 5 m at 1 m/s
        vehicle.tick(0.1)
    assert vehicle.last_node_id == "n2"
    assert vehicle.delays.injected == 1


def test_fleet_config_gives_each_vehicle_an_injector_only_when_asked() -> None:
    layout = Layout(
        map_id="m",
        nodes={"a": LayoutNode("a", 0.0, 0.0), "b": LayoutNode("b", 5.0, 0.0)},
        edges=(),
    )
    plain = build_vehicles(layout, FleetConfig(count=2))
    delayed = build_vehicles(layout, FleetConfig(count=2, delays=DelayConfig(share=0.05)))
    assert [v.delays for v in plain] == [None, None]
    assert all(v.delays is not None for v in delayed)


@pytest.mark.parametrize("text", ["5", "30,5", "1,2,3", "-1,2"])
def test_bad_delay_ranges_are_refused(text: str) -> None:
    with pytest.raises(ValueError, match="delay range"):
        parse_range(text)


def test_cli_takes_delay_and_summary_options() -> None:
    args = build_parser().parse_args(
        [
            "--count",
            "2",
            "--layout",
            "x.json",
            "--delay-share",
            "0.05",
            "--delay-range",
            "5,30",
            "--summary",
            "out.json",
        ]
    )
    assert (args.delay_share, parse_range(args.delay_range), args.summary) == (
        0.05,
        (5.0, 30.0),
        "out.json",
    )
    with pytest.raises(ValueError, match="share"):
        DelayConfig(share=1.5)
