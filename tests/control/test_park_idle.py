"""Idle vehicles in an order's way are sent to park (control/parking.py), in process.

The real Controller drives in-process simulated vehicles (as in test_traffic_controller.py) on a
one-lane corridor with two park spurs. An idle vehicle stands on the goal, or in the passage, of
the other vehicle's order: without parking that order never starts; with it the idle vehicle
is sent to a park station (a `vehicle.park` job, opened here like the flush would) and the order
finishes, with no collision seen by the simulator's checker.
"""

from collections import deque
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
from simulator.fleet import footprint_of
from simulator.vehicle import VirtualVehicle
from tests.control.fakes import FakeStore
from vda5050.enums import ConnectionState, TopicKind

SPACING = 2.0  # m between nodes: neighbours are free of each other


def corridor() -> LayoutIndex:
    """W1 … W5 in a row (one lane, both ways); park spurs PK-1 above W2 and PK-2 above W4."""
    nodes = {f"W{i}": NodePlace((i - 1) * SPACING, 0.0, None, "hall") for i in range(1, 6)}
    nodes["PK1"] = NodePlace(SPACING, SPACING, None, "hall")
    nodes["PK2"] = NodePlace(3 * SPACING, SPACING, None, "hall")
    pairs = [(f"W{i}", f"W{i + 1}") for i in range(1, 5)] + [("W2", "PK1"), ("W4", "PK2")]
    edges = {}
    for a, b in pairs:
        edges[(a, b)], edges[(b, a)] = f"{a}-{b}", f"{b}-{a}"
    return LayoutIndex("hall", nodes, edges, parking={"PARK-1": "PK1", "PARK-2": "PK2"})


LAYOUT = corridor()


def shortest(start: str, goal: str) -> list[str]:
    """Breadth-first route on LAYOUT (what the database's move would carry)."""
    previous: dict[str, str | None] = {start: None}
    queue = deque([start])
    while queue:
        node = queue.popleft()
        for a, b in LAYOUT.edges:
            if a == node and b not in previous:
                previous[b] = node
                queue.append(b)
    route = [goal]
    while (step := previous[route[-1]]) is not None:
        route.append(step)
    return route[::-1]


@dataclass
class Store(FakeStore):
    vehicles: list[str] = field(default_factory=list)

    def load_layouts(self) -> dict[str, LayoutIndex]:
        return {"hall": LAYOUT}

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


class World:
    """Two simulated vehicles and the controller; park jobs are opened like the flush does."""

    def __init__(self, starts: dict[str, str], *, park_idle: bool) -> None:
        self.vehicles: dict[str, VirtualVehicle] = {}
        known = {n: (p.x, p.y) for n, p in LAYOUT.nodes.items()}
        for serial, node in starts.items():
            place = LAYOUT.nodes[node]
            self.vehicles[serial] = VirtualVehicle(
                VehicleConfig(serial_number=serial, state_interval=1.0),
                StartPose("hall", node, place.x, place.y, 0.0),
                known_nodes=known,
            )
        self.serials = list(starts)
        self.footprints = {s: footprint_of(v) for s, v in self.vehicles.items()}
        self.checker = CollisionChecker()
        self.controller = Controller(
            store=Store(vehicles=self.serials),
            interface_name="uagv",
            publish=self.deliver,
            traffic=True,
            park_idle=park_idle,
        )
        self.controller.load()
        self.orders: list[ActiveOrder] = []
        self.finished: set[int] = set()
        self.park_jobs: list[dict[str, Any]] = []
        for serial, vehicle in self.vehicles.items():
            message = wire.connection(vehicle, ConnectionState.ONLINE)
            self.controller.handle_message(
                self.topic(serial, "connection"), vda5050.encode(message)
            )
            self.publish_state(serial)

    def transport(self, serial: str, pickup: str, drop: str) -> None:
        vehicle = self.vehicles[serial]
        self.orders.append(
            ActiveOrder(
                transport_order_id=len(self.orders) + 1,
                vda_order_id=f"TO-{len(self.orders) + 1}",
                vehicle_pk=self.serials.index(serial) + 1,
                route=shortest(vehicle.last_node_id, drop),
                pickup_node=pickup,
                map_id="hall",
                pick_station="PICK",
                drop_station="DROP",
            )
        )

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
        """Step until the transport orders finished or `seconds` of simulated time passed."""
        for step in range(int(seconds / dt)):
            if step % 10 == 0:
                self.controller.sync(
                    [o for o in self.orders if o.transport_order_id not in self.finished]
                )
                self.collect()
            for serial, vehicle in self.vehicles.items():
                vehicle.tick(dt)
                if vehicle.take_state_due() or step % 10 == 0:
                    self.publish_state(serial)
            bodies = [
                Body(s, v.x, v.y, v.theta, self.footprints[s]) for s, v in self.vehicles.items()
            ]
            self.checker.check(bodies, step * dt)
            if all(
                o.transport_order_id in self.finished for o in self.orders if o.kind == "transport"
            ):
                return

    def collect(self) -> None:
        batch = self.controller.collect_flush()
        self.finished |= {p.order_id for p in batch.progress if p.kind == "finished"}
        assert [p for p in batch.progress if p.kind in {"failed", "requeued"}] == []
        for job in batch.job_requests:  # what control.persistence._open_job makes of it
            assert job["kind"] == "vehicle.park"
            self.park_jobs.append(job)
            serial = self.serials[job["vehicle"] - 1]
            station = job["station"]
            number = len(self.park_jobs)
            self.orders.append(
                ActiveOrder(
                    transport_order_id=-(2 * number + 1),
                    vda_order_id=f"move-{number}",
                    vehicle_pk=job["vehicle"],
                    route=shortest(self.vehicles[serial].last_node_id, LAYOUT.parking[station]),
                    pickup_node=LAYOUT.parking[station],
                    map_id="hall",
                    pick_station=station,
                    drop_station=station,
                    kind="park",
                )
            )


@pytest.mark.parametrize("idle_at", ["W5", "W4"])  # on the goal; in the one-lane passage
def test_without_parking_the_order_never_starts(idle_at: str) -> None:
    world = World({"AGV-1": "W1", "AGV-2": idle_at}, park_idle=False)
    world.transport("AGV-1", "W3", "W5")

    world.run(60.0)

    assert world.finished == set()
    assert world.vehicles["AGV-1"].last_node_id == "W1"
    assert world.controller.fleet.vehicles[("sim", "AGV-1")].execution is None
    assert world.park_jobs == []
    assert world.controller.traffic is not None
    assert any("no plan for TO-1" in p for p in world.controller.traffic.problems)


@pytest.mark.parametrize("idle_at", ["W5", "W4"])
def test_the_idle_vehicle_parks_and_the_order_finishes(idle_at: str) -> None:
    world = World({"AGV-1": "W1", "AGV-2": idle_at}, park_idle=True)
    world.transport("AGV-1", "W3", "W5")

    world.run(120.0)

    assert 1 in world.finished
    assert world.vehicles["AGV-1"].last_node_id == "W5"
    # Sent once (not again at every failed plan), to the nearest free station: PK2, off W4.
    assert [(j["vehicle"], j["station"]) for j in world.park_jobs] == [(2, "PARK-2")]
    assert world.park_jobs[0]["reason"] == "in the way of order TO-1"
    assert world.vehicles["AGV-2"].last_node_id == "PK2"
    assert -3 in world.finished  # the move to the park station finished too
    assert world.checker.count == 0
    assert world.checker.steps > 100


def test_a_vehicle_left_on_a_station_after_its_order_is_parked_for_the_next() -> None:
    """AGV-2 ends its order on W5; AGV-1's later order to W5 gets it out of the way."""
    world = World({"AGV-1": "W1", "AGV-2": "W4"}, park_idle=True)
    world.transport("AGV-2", "W4", "W5")
    world.run(60.0)
    assert world.finished == {1}
    assert world.vehicles["AGV-2"].last_node_id == "W5"

    world.transport("AGV-1", "W2", "W5")
    world.run(120.0)

    assert 2 in world.finished
    assert [j["vehicle"] for j in world.park_jobs] == [2]
    assert world.vehicles["AGV-2"].last_node_id in {"PK1", "PK2"}
    assert world.checker.count == 0
