"""Many simulated vehicles on one thread: the lightweight runtime for load tests.

`SimulatedFleet` gives every vehicle its own paho network thread; at 1,000 vehicles that is
1,000 threads waking each other for every publish. Here the same :class:`VehicleLink` and
:class:`VirtualVehicle` (so the same protocol behaviour: orders, stitching, actions, state
events) run on paho's external-loop API instead: one selector over all sockets, publishes
written directly, and the vehicles ticked in slices so their messages spread over time like a
real fleet's rather than leaving in bursts. No footprint collision check (use the normal
runtime for that).

    python -m simulator.pump --count 1000 --layout layout.json --state-interval 1 --slices 20
"""

from __future__ import annotations

import logging
import random
import selectors
import signal
import sys
import threading
import time
from collections.abc import Sequence
from types import FrameType

import paho.mqtt.client as mqtt

from simulator import wire
from simulator.__main__ import build_parser, config_from_args, parse_broker
from simulator.fleet import FleetConfig, build_vehicles
from simulator.layout import LayoutError, load_layout
from simulator.mqtt import BrokerSettings, VehicleLink
from vda5050 import encode
from vda5050.enums import ConnectionState, TopicKind

log = logging.getLogger(__name__)

_MAX_TICK_SECONDS = 1.0
_MISC_INTERVAL = 1.0  # keep-alive pings and reconnects


class PumpFleet:
    """N vehicles, one thread: `run(stop)` connects them, ticks them and serves their sockets."""

    def __init__(self, links: list[VehicleLink], *, tick_hz: float, slices: int, seed: int = 1):
        self.links = links
        self.tick_hz = tick_hz
        self.slices = max(1, min(slices, len(links)))
        self.rng = random.Random(seed)
        self.selector = selectors.DefaultSelector()
        self.registered: dict[int, VehicleLink] = {}
        self.reconnects = 0
        self.backlog: set[VehicleLink] = set()  # links whose last write left bytes unsent

    def run(self, stop: threading.Event) -> None:
        """Connect every vehicle, then loop until `stop`; finish with OFFLINE + DISCONNECT."""
        for link in self.links:
            self._connect(link)
        self._stagger()
        groups = [self.links[i :: self.slices] for i in range(self.slices)]
        period = 1.0 / (self.tick_hz * self.slices)  # one slice per sub-tick
        last = [time.monotonic()] * self.slices
        index, next_tick, next_misc = 0, time.monotonic(), time.monotonic()
        while not stop.is_set():
            self._serve(max(0.0, next_tick - time.monotonic()))
            now = time.monotonic()
            if now >= next_tick:
                next_tick = max(next_tick + period, now)
                dt, last[index] = now - last[index], now
                for link in groups[index]:
                    if link.client.is_connected():
                        try:
                            link.pump(min(dt, _MAX_TICK_SECONDS), now)
                        except Exception:
                            log.exception("tick failed for %s", link.vehicle.config.serial_number)
                self._write_pending(groups[index])
                index = (index + 1) % self.slices
            if now >= next_misc:
                next_misc = now + _MISC_INTERVAL
                self._misc()
        self._shutdown()

    # ------------------------------------------------------------------ network
    def _connect(self, link: VehicleLink) -> None:
        broker = link.broker
        try:
            link.client.connect(broker.host, broker.port, broker.keepalive)
        except OSError as exc:
            log.warning("%s: connect failed: %s", link.vehicle.config.serial_number, exc)
            return
        self._register(link)

    def _register(self, link: VehicleLink) -> None:
        sock = link.client.socket()
        if sock is None:
            return
        self.selector.register(sock, selectors.EVENT_READ, link)
        self.registered[id(link)] = link

    def _unregister(self, link: VehicleLink) -> None:
        for key in list(self.selector.get_map().values()):
            if key.data is link:
                self.selector.unregister(key.fileobj)
        self.registered.pop(id(link), None)

    def _serve(self, timeout: float) -> None:
        for key, _events in self.selector.select(timeout):
            link: VehicleLink = key.data
            if link.client.loop_read() != mqtt.MQTT_ERR_SUCCESS:
                self._unregister(link)  # lost: reconnected by _misc
            elif link.client.want_write():  # answers queued inside callbacks (accept, state)
                link.client.loop_write()

    def _write_pending(self, ticked: Sequence[VehicleLink] | None = None) -> None:
        """Write what the just-ticked links published, and what a full socket held back before
        (asking every link after each of the 200 slices a second was a fifth of the pump's
        CPU); with no `ticked`, every link (once a second)."""
        links = list(self.registered.values()) if ticked is None else [*ticked, *self.backlog]
        self.backlog = set()
        for link in links:
            if id(link) in self.registered and link.client.want_write():
                link.client.loop_write()
                if link.client.want_write():
                    self.backlog.add(link)

    def _misc(self) -> None:
        for link in self.links:
            if id(link) not in self.registered:
                try:
                    link.client.reconnect()
                    self.reconnects += 1
                    self._register(link)
                except OSError:
                    continue
            elif link.client.loop_misc() != mqtt.MQTT_ERR_SUCCESS:
                self._unregister(link)
        self._write_pending()

    def _stagger(self) -> None:
        """Spread the periodic state and visualization of the vehicles over their period."""
        now = time.monotonic()
        for link in self.links:
            cfg = link.vehicle.config
            link._last_state = now - self.rng.random() * cfg.state_interval
            if cfg.visualization_hz > 0:
                link._last_visualization = now - self.rng.random() / cfg.visualization_hz

    def _shutdown(self) -> None:
        """Graceful stop: OFFLINE (retained) from every vehicle, then DISCONNECT."""
        for link in self.registered.values():
            with link.lock:
                offline = encode(wire.connection(link.vehicle, ConnectionState.OFFLINE))
            link.client.publish(link.topic(TopicKind.CONNECTION), offline, qos=1, retain=True)
        deadline = time.monotonic() + 2.0
        while time.monotonic() < deadline and any(
            link.client.want_write() for link in self.registered.values()
        ):
            self._write_pending()
            self._serve(0.05)
        self._serve(0.2)  # the PUBACKs
        for link in list(self.registered.values()):
            link.client.disconnect()
            link.client.loop_write()
        self.selector.close()


def build_pump(config: FleetConfig, layout_path: str, *, slices: int) -> PumpFleet:
    """A PumpFleet of `config.count` vehicles on the layout in `layout_path`."""
    broker = BrokerSettings(
        host=config.broker_host,
        port=config.broker_port,
        username=config.username,
        password=config.password,
        keepalive=config.keepalive,
    )
    layout = load_layout(layout_path)
    links = [
        VehicleLink(vehicle, broker, config.interface) for vehicle in build_vehicles(layout, config)
    ]
    return PumpFleet(links, tick_hz=config.tick_hz, slices=slices)


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point (the simulator's flags plus --slices); returns the exit code."""
    parser = build_parser()
    parser.prog = "python -m simulator.pump"
    parser.add_argument(
        "--slices", type=int, default=20, help="vehicles ticked in this many groups in turn"
    )
    args = parser.parse_args(argv)
    logging.basicConfig(
        level=args.log_level.upper(), format="%(asctime)s %(levelname)s %(name)s: %(message)s"
    )
    logging.getLogger("simulator.mqtt").setLevel(logging.WARNING)  # a line per order otherwise
    try:
        config = config_from_args(args, parse_broker(args.broker))
        fleet = build_pump(config, args.layout, slices=args.slices)
    except (ValueError, LayoutError) as exc:
        parser.error(str(exc))
    stop = threading.Event()

    def request_stop(signum: int, _frame: FrameType | None) -> None:
        stop.set()

    signal.signal(signal.SIGTERM, request_stop)
    signal.signal(signal.SIGINT, request_stop)
    log.info(
        "pump: %d vehicles on %s:%d interface %r",
        config.count,
        config.broker_host,
        config.broker_port,
        args.interface,
    )
    fleet.run(stop)
    log.info("pump stopped (%d reconnects)", fleet.reconnects)
    return 0


if __name__ == "__main__":
    sys.exit(main())
