"""The controller with traffic management, driving in-process simulated vehicles on crossing routes.

No MQTT and no database: the controller publishes into the vehicles' `on_order`, the vehicles'
state messages go into `handle_message`, and the simulator's own collision checker watches every
simulated step. The same run without traffic management must collide (the check can fail).
"""

import math
from typing import Any

import pytest

import vda5050
from control.execution import LayoutIndex, NodePlace
from control.metrics import ControlMetrics
from control.ports import ActiveOrder
from simulator import wire
from simulator.delays import DelayConfig, DelayInjector
from tests.control.sim_world import SimWorld

SPACING = 2.0  # m between nodes: adjacent nodes are free of each other, the crossing is shared
ARMS = {"W": (-1, 0), "E": (1, 0), "N": (0, 1), "S": (0, -1)}


def crossing() -> LayoutIndex:
    """A plus-shaped layout: arms W, E, N, S of three nodes each around the centre node C."""
    nodes = {"C": NodePlace(0.0, 0.0, None, "cross")}
    edges: dict[tuple[str, str], str] = {}
    for arm, (dx, dy) in ARMS.items():
        previous = "C"
        for i in (1, 2, 3):
            node = f"{arm}{i}"
            nodes[node] = NodePlace(dx * i * SPACING, dy * i * SPACING, None, "cross")
            edges[(previous, node)] = f"{previous}-{node}"
            edges[(node, previous)] = f"{node}-{previous}"
            previous = node
    return LayoutIndex("cross", nodes, edges)


LAYOUT = crossing()
# Vehicle: (start, pickup, drop). Through the centre, all at the same distance; AGV-3 drives
# head-on into the arms AGV-1 and AGV-2 use, and ends where AGV-1 starts.
JOBS = {
    "AGV-1": ("W3", "W2", "E3"),
    "AGV-2": ("N3", "N2", "S3"),
    "AGV-3": ("S3", "S2", "W3"),
}


def straight(start: str, drop: str) -> list[str]:
    """The straight route between two arm nodes through C."""
    arm_a, a = start[0], int(start[1])
    arm_b, b = drop[0], int(drop[1])
    return (
        [f"{arm_a}{i}" for i in range(a, 0, -1)] + ["C"] + [f"{arm_b}{i}" for i in range(1, b + 1)]
    )


class World(SimWorld):
    """The JOBS vehicles on the crossing, each with its order."""

    def __init__(self, serials: list[str], *, traffic: bool, delays: DelayConfig | None = None):
        # without traffic: the whole route at once (base_ahead None)
        starts = {serial: JOBS[serial][0] for serial in serials}
        super().__init__(LAYOUT, starts, base_ahead=None, traffic=traffic)
        if delays is not None:
            for i, vehicle in enumerate(self.vehicles.values()):
                vehicle.delays = DelayInjector(delays, stream=i)
        self.orders = [
            ActiveOrder(
                transport_order_id=i + 1,
                vda_order_id=f"TO-{i + 1}",
                vehicle_pk=i + 1,
                route=straight(JOBS[s][0], JOBS[s][2]),
                pickup_node=JOBS[s][1],
                map_id="cross",
                pick_station="P",
                drop_station="D",
            )
            for i, s in enumerate(serials)
        ]


def test_vehicles_on_crossing_routes_all_arrive_without_collision() -> None:
    world = World(["AGV-1", "AGV-2", "AGV-3"], traffic=True)

    world.run(120.0)

    assert world.finished == {1, 2, 3}
    assert world.checker.count == 0
    assert world.checker.steps > 100
    last = {s: v.last_node_id for s, v in world.vehicles.items()}
    assert last == {"AGV-1": "E3", "AGV-2": "S3", "AGV-3": "W3"}
    traffic = world.controller.traffic
    assert traffic is not None
    assert traffic.safety(math.inf) == {"cycles": 0, "stalled": 0}


def test_someone_waited_for_someone_at_the_crossing() -> None:
    world = World(["AGV-1", "AGV-2"], traffic=True)
    traffic = world.controller.traffic
    assert traffic is not None
    waits: set[tuple[str, str]] = set()
    for _ in range(60):
        world.run(1.0)
        for serial in world.vehicles:
            live = world.controller.fleet.vehicles[("sim", serial)]
            waits |= {(serial, other) for other in traffic.waiting_for(live)}
    assert world.finished == {1, 2}
    assert waits in ({("AGV-1", "AGV-2")}, {("AGV-2", "AGV-1")})
    assert world.checker.count == 0


def test_delayed_moves_still_finish_without_collision() -> None:
    delays = DelayConfig(share=0.3, low=2.0, high=8.0, seed=7)
    world = World(["AGV-1", "AGV-2", "AGV-3"], traffic=True, delays=delays)

    world.run(300.0)

    assert sum(v.delays.injected for v in world.vehicles.values() if v.delays) > 0
    assert world.finished == {1, 2, 3}
    assert world.checker.count == 0


@pytest.mark.parametrize("serials", [["AGV-1", "AGV-2"]])
def test_without_traffic_management_the_same_routes_collide(serials) -> None:
    world = World(serials, traffic=False)

    world.run(120.0)

    assert world.checker.count >= 1  # the checker sees what traffic management prevents


def test_live_rows_show_whom_a_vehicle_waits_for_and_its_reservations() -> None:
    world = World(["AGV-1", "AGV-2"], traffic=True)
    seen: list[dict[str, Any]] = []
    for _ in range(60):
        world.run(0.5)
        rows = world.controller.all_browser_rows()
        seen += [r for r in rows if r["waiting_for"]]
        if seen:
            break
    assert seen, "nobody waited at the crossing"
    row = seen[0]
    other = {"AGV-1": "AGV-2", "AGV-2": "AGV-1"}[row["serial"]]
    assert row["waiting_for"] == [other]
    # Reserved: the planned nodes beyond its base, as map positions.
    assert row["reserved"]
    assert all(len(point) == 2 for point in row["reserved"])
    assert [0.0, 0.0] in row["reserved"]  # the crossing it waits to enter


def test_a_vehicle_offline_mid_order_is_an_obstacle_then_readopted_and_finishes() -> None:
    world = World(["AGV-1", "AGV-2", "AGV-3"], traffic=True)
    world.run(3.0)
    traffic = world.controller.traffic
    assert traffic is not None
    live = world.controller.fleet.vehicles[("sim", "AGV-1")]
    assert live.execution is not None
    live.session.last_alive_at = -1e9  # its states stopped coming long ago
    world.controller.sync(world.orders)

    assert traffic.tracked["sim/AGV-1"].static == "offline"
    assert traffic.lost(live, live.execution.vda_order_id)

    world.run(200.0)  # it reports again: re-planned at its decision point

    assert world.finished == {1, 2, 3}
    assert world.checker.count == 0
    assert traffic.tracked["sim/AGV-1"].static is None
    assert not any("beyond" in p for p in traffic.problems)


def test_metrics_carry_the_safety_net_and_count_traffic_problems() -> None:
    world = World(["AGV-1", "AGV-2"], traffic=True)
    world.run(1.0)
    metrics = ControlMetrics(world.controller)
    snapshot = metrics.snapshot()
    assert snapshot["traffic_safety"] == {"cycles": 0, "stalled": 0}
    assert snapshot["counters"]["traffic_problems"] == 0

    # A third vehicle reports standing where AGV-1 is registered: traffic cannot place it.
    for state in wire.states(world.vehicles["AGV-1"]):
        payload = vda5050.encode(state).replace(b'"AGV-1"', b'"AGV-9"')
        world.controller.handle_message(World.topic("AGV-9", "state"), payload)

    assert metrics.snapshot()["counters"]["traffic_problems"] == 1
    traffic = world.controller.traffic
    assert traffic is not None
    assert any(p.startswith("cannot place sim/AGV-9") for p in traffic.problems)
