"""The controller and simulated vehicles in one process, on the real database (no MQTT).

Vehicles' messages go straight into `Controller.handle_message`, the controller's orders and
instant actions straight back into the vehicles; `step()` advances simulated time and runs
what `control`'s loop runs (sync, flush with the alert/inventory hook). Time in the
controller's session and in the alert/inventory observers is a fake monotonic clock, so
timeouts and "no progress for N s" take no wall time.
"""

from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

from control.controller import Controller
from control.persistence import DjangoStore
from maps.models import Map
from maps.selectors import layout_as_dict
from simulator import wire
from simulator.fleet import FleetConfig, build_vehicles
from simulator.layout import Layout
from simulator.load_faults import LoadFaults
from simulator.vehicle import VirtualVehicle
from vda5050 import encode
from vda5050.enums import ConnectionState, TopicKind


@dataclass
class Clock:
    now: float = 1000.0

    def __call__(self) -> float:
        return self.now


@dataclass
class Harness:
    layout: Map
    count: int = 1
    version: str = "2.0.0"
    clock: Clock = field(default_factory=Clock)
    vehicles: list[VirtualVehicle] = field(default_factory=list)
    faults: dict[str, LoadFaults] = field(default_factory=dict)
    silent: set[str] = field(default_factory=set)
    controller: Controller = field(init=False)

    def __post_init__(self) -> None:
        sim_layout = Layout.from_dict(layout_as_dict(map=self.layout))
        config = FleetConfig(count=self.count, version=self.version, time_scale=1.0, speed=2.0)
        self.vehicles = build_vehicles(sim_layout, config)
        self.faults = {v.config.serial_number: LoadFaults() for v in self.vehicles}
        self.controller = Controller(
            store=DjangoStore(), interface_name="uagv", publish=self._route
        )
        self.controller.load()
        for vehicle in self.vehicles:
            self.send(
                vehicle, TopicKind.CONNECTION, wire.connection(vehicle, ConnectionState.ONLINE)
            )
            self.publish_state(vehicle)
        self.sync_and_flush()  # registers the vehicles
        self.step(1)  # now their snapshots have rows to go to

    # topics ---------------------------------------------------------------------------------
    def topic(self, vehicle: VirtualVehicle, kind: str) -> str:
        major = "v3" if vehicle.config.major >= 3 else "v2"
        return f"uagv/{major}/{vehicle.config.manufacturer}/{vehicle.config.serial_number}/{kind}"

    def send(self, vehicle: VirtualVehicle, kind: TopicKind, message: Any) -> None:
        self.controller.handle_message(self.topic(vehicle, kind.value), encode(message))

    def publish_state(self, vehicle: VirtualVehicle) -> None:
        if vehicle.config.serial_number in self.silent:
            return
        for state in wire.states(vehicle):
            self.send(vehicle, TopicKind.STATE, state)

    def _route(self, topic: str, payload: bytes, qos: int) -> None:
        serial, kind = topic.split("/")[3], topic.rsplit("/", 1)[1]
        vehicle = self.vehicle(serial)
        if kind == "order":
            vehicle.on_order(wire.decode_inbound(TopicKind.ORDER, payload, vehicle.config.version))
        elif kind == "instantActions":
            message = wire.decode_inbound(
                TopicKind.INSTANT_ACTIONS, payload, vehicle.config.version
            )
            vehicle.on_instant_actions(message)  # type: ignore[arg-type]

    def vehicle(self, serial: str = "AGV-1") -> VirtualVehicle:
        return next(v for v in self.vehicles if v.config.serial_number == serial)

    # time -----------------------------------------------------------------------------------
    def sync_and_flush(self) -> None:
        self.controller.sync(self.controller.store.active_orders())
        self.controller.flush()

    def step(self, seconds: float = 1.0, tick: float = 0.25) -> None:
        """Advance every vehicle `seconds` in ticks; publish due states; then sync + flush."""
        elapsed = 0.0
        while elapsed < seconds - 1e-9:
            self.clock.now += tick
            elapsed += tick
            for vehicle in self.vehicles:
                before = list(vehicle.loads)
                vehicle.tick(tick)
                self.faults[vehicle.config.serial_number].after_tick(vehicle, before)
                if vehicle.take_state_due():
                    self.publish_state(vehicle)
        for vehicle in self.vehicles:
            vehicle.mark_state_due()  # a state at least every step, like a 1 s state interval
            if vehicle.take_state_due():
                self.publish_state(vehicle)
        self.sync_and_flush()

    def run_until(self, done: Callable[[], bool], limit: float = 300.0, step: float = 1.0) -> float:
        start = self.clock.now
        while not done():
            if self.clock.now - start > limit:
                raise AssertionError(f"not done after {limit} simulated seconds")
            self.step(step)
        return self.clock.now - start
