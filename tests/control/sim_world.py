"""In-process simulated vehicles wired to a real Controller: no MQTT and no database.

The controller publishes into the vehicles' `on_order`/`on_instant_actions`, the vehicles' state
messages go into `handle_message`, and the simulator's own collision checker watches every
simulated step. Used by the traffic and parking tests, each with its own layout and orders.
"""

from dataclasses import dataclass, field
from typing import Any

import vda5050
from control.controller import Controller
from control.execution import LayoutIndex
from control.ports import ActiveOrder
from simulator import wire
from simulator.collisions import Body, CollisionChecker
from simulator.config import StartPose, VehicleConfig
from simulator.fleet import footprint_of
from simulator.vehicle import VirtualVehicle
from tests.control.fakes import FakeStore
from vda5050.enums import ConnectionState, TopicKind


@dataclass
class LayoutStore(FakeStore):
    """A store with one layout and the given vehicles (pk = position + 1)."""

    layout: LayoutIndex | None = None
    vehicles: list[str] = field(default_factory=list)

    def load_layouts(self) -> dict[str, LayoutIndex]:
        assert self.layout is not None
        return {self.layout.map_id: self.layout}

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


class SimWorld:
    """Vehicles starting at `starts` (serial -> node), stepped with a fixed simulated time step;
    `controller_options` go to the Controller. Subclasses add orders to `self.orders`."""

    def __init__(
        self, layout: LayoutIndex, starts: dict[str, str], **controller_options: Any
    ) -> None:
        self.layout = layout
        self.serials = list(starts)
        known = {n: (p.x, p.y) for n, p in layout.nodes.items()}
        self.vehicles: dict[str, VirtualVehicle] = {}
        for serial, node in starts.items():
            place = layout.nodes[node]
            self.vehicles[serial] = VirtualVehicle(
                VehicleConfig(serial_number=serial, state_interval=1.0),
                StartPose(layout.map_id, node, place.x, place.y, 0.0),
                known_nodes=known,
            )
        self.footprints = {s: footprint_of(v) for s, v in self.vehicles.items()}
        self.checker = CollisionChecker()
        self.controller = Controller(
            store=LayoutStore(layout=layout, vehicles=self.serials),
            interface_name="uagv",
            publish=self.deliver,
            **controller_options,
        )
        self.controller.load()
        self.orders: list[ActiveOrder] = []
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
        vehicle = self.vehicles.get(serial)
        if vehicle is None:
            return  # a vehicle this world does not simulate: nobody receives it
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
        """Take the controller's flush batch: finished orders; none may fail or be requeued."""
        batch = self.controller.collect_flush()
        self.finished |= {p.order_id for p in batch.progress if p.kind == "finished"}
        assert [p for p in batch.progress if p.kind in {"failed", "requeued"}] == []
        self.take_jobs(batch.job_requests)

    def take_jobs(self, jobs: list[dict[str, Any]]) -> None:
        """Jobs the flush would open (charge, park): ignored unless a test opens them."""
