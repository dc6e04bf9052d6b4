"""N virtual vehicles in one process, all advanced by a single tick-loop thread.

Programmatic API used by the CLI and by tests::

    fleet = SimulatedFleet(load_layout("layout.json"), FleetConfig(count=3))
    fleet.start()
    fleet.wait_connected(5.0)
    ...
    fleet.stop()   # every vehicle publishes OFFLINE, then disconnects

Misbehaviour for conformance tests (see :mod:`simulator.misbehaviour`)::

    fleet.misbehave("AGV-2", reject_orders="orderError", reject_count=1)
    fleet.misbehave("AGV-2")   # behave again
"""

from __future__ import annotations

import logging
import threading
import time
from collections.abc import Iterator, Mapping
from contextlib import contextmanager
from dataclasses import dataclass, field, replace
from types import TracebackType
from typing import Any

from simulator.collisions import Body, CollisionChecker, Footprint
from simulator.delays import DelayConfig, DelayInjector
from simulator.factsheet import build_factsheet
from simulator.layout import Layout
from simulator.misbehaviour import Misbehaviour
from simulator.mqtt import KEEPALIVE_SECONDS, BrokerSettings, VehicleLink
from simulator.vehicle import StartPose, VehicleConfig, VirtualVehicle
from vda5050.enums import ErrorLevel, OperatingMode

log = logging.getLogger(__name__)


@dataclass(frozen=True, slots=True)
class FleetConfig:
    """Everything the CLI flags configure."""

    count: int = 1
    broker_host: str = "127.0.0.1"
    broker_port: int = 1883
    username: str | None = None
    password: str | None = None
    interface: str = "uagv"
    manufacturer: str = "sim"
    version: str = "2.0.0"
    speed: float = 1.0
    time_scale: float = 1.0
    visualization_hz: float = 1.0
    state_interval: float = 30.0
    serial_prefix: str = "AGV-"
    tick_hz: float = 10.0
    keepalive: int = KEEPALIVE_SECONDS
    misbehaviours: Mapping[str, Misbehaviour] = field(default_factory=dict)
    """Scripted misbehaviour by serial number (``--misbehave`` / ``--script``)."""
    delays: DelayConfig = DelayConfig()
    """A share of moves delayed by a random time (``--delay-share``, ``--delay-range``)."""

    def serial(self, index: int) -> str:
        """Serial number of vehicle ``index`` (0-based): prefix + 1-based number."""
        return f"{self.serial_prefix}{index + 1}"


def build_vehicles(layout: Layout, config: FleetConfig) -> list[VirtualVehicle]:
    """Create the vehicles on their start nodes (parking[i % len] or nodes[i])."""
    known = {node_id: (node.x, node.y) for node_id, node in layout.nodes.items()}
    vehicles = []
    for i in range(config.count):
        node = layout.start_node(i)
        start = StartPose(layout.map_id, node.node_id, node.x, node.y, layout.start_heading(node))
        vehicle_config = VehicleConfig(
            serial_number=config.serial(i),
            manufacturer=config.manufacturer,
            version=config.version,
            speed=config.speed,
            time_scale=config.time_scale,
            state_interval=config.state_interval,
            visualization_hz=config.visualization_hz,
            misbehaviour=config.misbehaviours.get(config.serial(i), Misbehaviour()),
        )
        vehicle = VirtualVehicle(vehicle_config, start, known_nodes=known)
        if config.delays.share > 0:
            vehicle.delays = DelayInjector(config.delays, stream=i)
        vehicles.append(vehicle)
    return vehicles


def footprint_of(vehicle: VirtualVehicle) -> Footprint:
    """The rectangle a vehicle's factsheet declares (physicalParameters length × width)."""
    physical = build_factsheet(
        header_id=0,
        timestamp="",
        version=vehicle.config.version,
        manufacturer=vehicle.config.manufacturer,
        serial_number=vehicle.config.serial_number,
        speed_max=vehicle.config.speed,
        state_interval=vehicle.config.state_interval,
        visualization_hz=vehicle.config.visualization_hz,
        with_vehicle_config=False,
    ).physical_parameters
    return Footprint(physical.length, physical.width)


class SimulatedFleet:
    """Runs N :class:`VirtualVehicle` over MQTT (one paho client each) plus one tick thread."""

    def __init__(self, layout: Layout, config: FleetConfig | None = None) -> None:
        self.config = config or FleetConfig()
        if self.config.count < 1:
            raise ValueError("count must be at least 1")
        serials = {self.config.serial(i) for i in range(self.config.count)}
        unknown = sorted(set(self.config.misbehaviours) - serials)
        if unknown:
            raise ValueError(f"misbehaviour for unknown vehicles {unknown}")
        broker = BrokerSettings(
            host=self.config.broker_host,
            port=self.config.broker_port,
            username=self.config.username,
            password=self.config.password,
            keepalive=self.config.keepalive,
        )
        self.layout = layout
        self.links = [
            VehicleLink(vehicle, broker, self.config.interface)
            for vehicle in build_vehicles(layout, self.config)
        ]
        self._by_serial = {link.vehicle.config.serial_number: link for link in self.links}
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None
        # Independent of control: footprints from the vehicles' own factsheets, every step.
        self.collisions = CollisionChecker()
        self._footprints = [footprint_of(link.vehicle) for link in self.links]

    # ------------------------------------------------------------------ lifecycle
    def start(self) -> None:
        """Connect every vehicle and start the tick loop (returns immediately)."""
        if self._thread is not None:
            raise RuntimeError("fleet already started")
        for link in self.links:
            link.start()
        self._stop.clear()
        self._thread = threading.Thread(target=self._run, name="simulator-tick", daemon=True)
        self._thread.start()
        log.info("started %d simulated vehicles", len(self.links))

    def stop(self) -> None:
        """Stop ticking, then publish OFFLINE and disconnect every vehicle."""
        self._stop.set()
        if self._thread is not None:
            self._thread.join(timeout=5.0)
            self._thread = None
        for link in self.links:
            try:
                link.stop()
            except Exception:
                log.exception("error stopping %s", link.vehicle.config.serial_number)
        log.info("stopped %d simulated vehicles", len(self.links))

    def wait_connected(self, timeout: float) -> bool:
        """Block until every vehicle is connected (True) or ``timeout`` expires (False)."""
        deadline = time.monotonic() + timeout
        return all(
            link.connected.wait(max(0.0, deadline - time.monotonic())) for link in self.links
        )

    def __enter__(self) -> SimulatedFleet:
        self.start()
        return self

    def __exit__(
        self,
        _exc_type: type[BaseException] | None,
        _exc: BaseException | None,
        _tb: TracebackType | None,
    ) -> None:
        self.stop()

    def _run(self) -> None:
        period = 1.0 / self.config.tick_hz
        last = time.monotonic()
        next_tick = last + period
        while not self._stop.wait(max(0.0, next_tick - time.monotonic())):
            now = time.monotonic()
            dt, last = now - last, now
            # Fixed-rate schedule; after a long stall resynchronise instead of bursting.
            next_tick = max(next_tick + period, now)
            for link in self.links:
                try:
                    link.pump(dt, now)
                except Exception:
                    log.exception("tick failed for %s", link.vehicle.config.serial_number)
            try:
                self.check_collisions()
            except Exception:  # the check must never stop the simulation
                log.exception("collision check failed")

    def check_collisions(self) -> int:
        """Check every vehicle's footprint against all others now; returns new collisions."""
        bodies = []
        for link, footprint in zip(self.links, self._footprints, strict=True):
            v = link.vehicle
            bodies.append(Body(v.config.serial_number, v.x, v.y, v.theta, footprint))
        sim_time = max(link.vehicle.sim_time for link in self.links)
        return len(self.collisions.check(bodies, sim_time))

    def summary(self) -> dict[str, object]:
        """What the run saw: collisions (must be 0) and injected delays."""
        delays = [link.vehicle.delays for link in self.links if link.vehicle.delays is not None]
        return {
            "vehicles": len(self.links),
            **self.collisions.summary(),
            "delays_injected": sum(d.injected for d in delays),
            "delay_seconds": round(sum(d.delayed_seconds for d in delays), 1),
        }

    # ------------------------------------------------------------------ access and faults
    @property
    def serials(self) -> list[str]:
        """Serial numbers of all vehicles, in creation order."""
        return list(self._by_serial)

    def link(self, serial: str) -> VehicleLink:
        """The MQTT runtime of one vehicle (KeyError for unknown serials)."""
        return self._by_serial[serial]

    @contextmanager
    def vehicle(self, serial: str) -> Iterator[VirtualVehicle]:
        """Lock and yield one vehicle, e.g. to inspect it or inject faults from tests."""
        link = self._by_serial[serial]
        with link.lock:
            yield link.vehicle
        link.flush()

    def inject_error(
        self, serial: str, error_type: str, level: ErrorLevel = ErrorLevel.WARNING
    ) -> None:
        """Make a vehicle report an error until :meth:`clear_errors`."""
        with self.vehicle(serial) as vehicle:
            vehicle.inject_error(error_type, level)

    def clear_errors(self, serial: str, error_type: str | None = None) -> None:
        """Remove injected errors of a vehicle."""
        with self.vehicle(serial) as vehicle:
            vehicle.clear_injected_errors(error_type)

    def set_silent(self, serial: str, silent: bool = True, duration: float | None = None) -> None:
        """Stop (or resume) state/visualization publishing while staying connected; with
        ``duration`` (simulated seconds) the vehicle resumes by itself afterwards."""
        if duration is not None and silent:
            with self.vehicle(serial) as vehicle:
                vehicle.saboteur.silence(duration)
            return
        self._by_serial[serial].silent = silent
        if not silent:
            with self.vehicle(serial) as vehicle:
                vehicle.saboteur.silence(0.0)
                vehicle.mark_state_due()

    def break_connection(self, serial: str, duration: float | None = None) -> None:
        """Drop a vehicle's TCP connection: broker sends CONNECTIONBROKEN, paho reconnects
        (after ``duration`` simulated seconds, if given) and publishes ONLINE again."""
        self._by_serial[serial].break_connection(duration)

    def misbehave(
        self, serial: str, misbehaviour: Misbehaviour | None = None, **changes: Any
    ) -> Misbehaviour:
        """Replace a vehicle's scripted misbehaviour; keywords are :class:`Misbehaviour`
        fields (applied on top of ``misbehaviour``). ``misbehave(serial)`` = behave again.
        Times count from now."""
        plan = replace(misbehaviour or Misbehaviour(), **changes)
        with self.vehicle(serial) as vehicle:
            vehicle.misbehave(plan)
        return plan

    def set_operating_mode(self, serial: str, mode: OperatingMode | str) -> None:
        """Switch a vehicle's operating mode (MANUAL/SERVICE/TEACHIN clear its order)."""
        with self.vehicle(serial) as vehicle:
            vehicle.set_operating_mode(OperatingMode(mode))
