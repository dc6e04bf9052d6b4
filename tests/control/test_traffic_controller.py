"""The controller with traffic management, driving in-process simulated vehicles on crossing routes.

No MQTT and no database: the controller publishes into the vehicles' `on_order`, the vehicles'
state messages go into `handle_message`, and the simulator's own collision checker watches every
simulated step. The same run without traffic management must collide (the check can fail).
"""

import math
from dataclasses import dataclass, field
from typing import Any

import pytest

import vda5050
from control.controller import Controller
from control.execution import LayoutIndex, NodePlace
from control.ports import ActiveOrder
from simulator import wire
from simulator.collisions import Body, CollisionChecker
from simulator.config import StartPose, VehicleConfig
from simulator.delays import DelayConfig, DelayInjector
from simulator.fleet import footprint_of
from simulator.vehicle import VirtualVehicle
from tests.control.fakes import FakeStore
from vda5050.enums import ConnectionState, TopicKind

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


@dataclass
class Store(FakeStore):
    vehicles: list[str] = field(default_factory=list)

    def load_layouts(self) -> dict[str, LayoutIndex]:
        return {"cross": LAYOUT}

    def load_vehicles(self) -> list[dict[str, Any]]:
        return [
            {
                "pk": i + 1,
                "manufacturer": "sim",
                "serial_number": serial,
                "interface_name": "uagv",
                "protocol_version": "2.0.0",
            }
            for i, serial in enumerate(self.vehicles)
        ]


def straight(start: str, drop: str) -> list[str]:
    """The straight route between two arm nodes through C."""
    arm_a, a = start[0], int(start[1])
    arm_b, b = drop[0], int(drop[1])
    return (
        [f"{arm_a}{i}" for i in range(a, 0, -1)] + ["C"] + [f"{arm_b}{i}" for i in range(1, b + 1)]
    )


class World:
    """Simulated vehicles wired to a controller, stepped with a fixed simulated time step."""

    def __init__(self, serials: list[str], *, traffic: bool, delays: DelayConfig | None = None):
        self.vehicles: dict[str, VirtualVehicle] = {}
        for i, serial in enumerate(serials):
            node = JOBS[serial][0]
            place = LAYOUT.nodes[node]
            start = StartPose("cross", node, place.x, place.y, 0.0)
            known = {n: (p.x, p.y) for n, p in LAYOUT.nodes.items()}
            vehicle = VirtualVehicle(
                VehicleConfig(serial_number=serial, state_interval=1.0),
                start,
                known_nodes=known,
            )
            if delays is not None:
                vehicle.delays = DelayInjector(delays, stream=i)
            self.vehicles[serial] = vehicle
        self.footprints = {s: footprint_of(v) for s, v in self.vehicles.items()}
        self.checker = CollisionChecker()
        self.controller = Controller(
            store=Store(vehicles=serials),
            interface_name="uagv",
            publish=self.deliver,
            base_ahead=None,  # without traffic: the whole route at once
            traffic=traffic,
        )
        self.controller.load()
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
        self.finished: set[int] = set()
        for serial, vehicle in self.vehicles.items():
            message = wire.connection(vehicle, ConnectionState.ONLINE)
            self.controller.handle_message(
                self.topic(serial, "connection"), vda5050.encode(message)
            )
            self.publish_state(serial)

    @staticmethod
    def topic(serial: str, kind: str) -> str:
        return f"uagv/v2/sim/{serial}/{kind}"

    def deliver(self, topic: str, payload: bytes, qos: int) -> None:
        serial, kind = topic.split("/")[-2:]
        vehicle = self.vehicles[serial]
        if kind == "order":
            vehicle.on_order(wire.decode_inbound(TopicKind.ORDER, payload, "2.0.0"))  # type: ignore[arg-type]
        elif kind == "instantActions":
            message = wire.decode_inbound(TopicKind.INSTANT_ACTIONS, payload, "2.0.0")
            vehicle.on_instant_actions(message)  # type: ignore[arg-type]

    def publish_state(self, serial: str) -> None:
        for state in wire.states(self.vehicles[serial]):
            self.controller.handle_message(self.topic(serial, "state"), vda5050.encode(state))

    def run(self, seconds: float, dt: float = 0.1) -> None:
        """Step until every order finished or `seconds` of simulated time passed."""
        steps = int(seconds / dt)
        for step in range(steps):
            if step % 10 == 0:
                self.controller.sync(
                    [o for o in self.orders if o.transport_order_id not in self.finished]
                )
                self.collect()
            for serial, vehicle in self.vehicles.items():
                vehicle.tick(dt)
                if vehicle.take_state_due() or step % 10 == 0:
                    self.publish_state(serial)
            self.checker.check(
                [Body(s, v.x, v.y, v.theta, self.footprints[s]) for s, v in self.vehicles.items()],
                step * dt,
            )
            if len(self.finished) == len(self.orders):
                return

    def collect(self) -> None:
        batch = self.controller.collect_flush()
        self.finished |= {p.order_id for p in batch.progress if p.kind == "finished"}
        failed = [p for p in batch.progress if p.kind in {"failed", "requeued"}]
        assert failed == []


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
