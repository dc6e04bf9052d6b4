"""MQTT wiring of one virtual vehicle: its own paho client, last will and publishing.

One client per vehicle is deliberate: the last will (CONNECTIONBROKEN, 3.0
CONNECTION_BROKEN) is per MQTT connection, so vehicles sharing a client could not report
their connection separately. Messages go through :mod:`simulator.wire`, which speaks the
vehicle's protocol version (topics ``.../v2/...`` or ``.../v3/...``).
paho runs each client's network loop in its own thread; every callback is wrapped so an
exception is logged instead of killing that thread.
"""

from __future__ import annotations

import logging
import math
import socket
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import paho.mqtt.client as mqtt
from paho.mqtt.enums import CallbackAPIVersion
from paho.mqtt.reasoncodes import ReasonCode

from simulator import wire
from simulator.vehicle import VirtualVehicle
from vda5050 import (
    DecodeError,
    InstantActions,
    Order,
    Topic,
    decode,
    encode,
    major_version_of,
    v3,
)
from vda5050.enums import ConnectionState, TopicKind

log = logging.getLogger(__name__)

#: REFERENCE §2: keep-alive "around 15 s".
KEEPALIVE_SECONDS = 15
#: Longest wait for the broker to acknowledge OFFLINE before disconnecting anyway.
STOP_TIMEOUT_SECONDS = 3.0
# A stalled tick loop (debugger, suspended laptop) must not teleport vehicles.
_MAX_TICK_SECONDS = 1.0
#: paho's reconnect back-off after an ordinary connection loss, in seconds.
RECONNECT_DELAY = (1, 30)


@dataclass(frozen=True, slots=True)
class BrokerSettings:
    """Where and how to connect."""

    host: str = "127.0.0.1"
    port: int = 1883
    username: str | None = None
    password: str | None = None
    keepalive: int = KEEPALIVE_SECONDS


def _guarded(name: str, func: Callable[..., None]) -> Callable[..., None]:
    """Wrap a paho callback so an exception is logged and never reaches the network thread."""

    def wrapper(*args: Any) -> None:
        try:
            func(*args)
        except Exception:
            log.exception("error in MQTT %s callback", name)

    return wrapper


def _on_grid(last: float, period: float, now: float) -> float:
    """The send time to count the next `period` from: one period after `last`, or `now` after
    a stall (two periods or more), so a late tick never bursts to catch up."""
    return now if now - last >= 2 * period else last + period


class VehicleLink:
    """Runs one :class:`VirtualVehicle` on MQTT: subscribes to its order/instantActions
    topics and publishes connection, factsheet, state and visualization.

    All access to the vehicle happens under :attr:`lock`, because both the paho network
    thread (incoming messages) and the fleet's tick thread touch it.
    """

    def __init__(self, vehicle: VirtualVehicle, broker: BrokerSettings, interface: str) -> None:
        self.vehicle = vehicle
        self.broker = broker
        self.lock = threading.Lock()
        self.connected = threading.Event()  # set once the broker acknowledged ONLINE
        self._online_mid = -1
        self.silent = False  # fault injection: stop publishing state/visualization
        cfg = vehicle.config
        self._version = cfg.version
        self._topic = Topic(
            interface_name=interface,
            major_version=major_version_of(cfg.version),
            manufacturer=cfg.manufacturer,
            serial_number=cfg.serial_number,
            kind=TopicKind.STATE,
        )
        self._inbound = {
            self.topic(TopicKind.ORDER): TopicKind.ORDER,
            self.topic(TopicKind.INSTANT_ACTIONS): TopicKind.INSTANT_ACTIONS,
        }
        if cfg.major >= 3:  # 3.0 zone sets (REFERENCE L.48), stored by simulator.maps
            self._inbound[self.topic(TopicKind.ZONE_SET)] = TopicKind.ZONE_SET
            self._inbound[self.topic(TopicKind.RESPONSES)] = TopicKind.RESPONSES
        self._last_state = float("-inf")
        self._last_visualization = float("-inf")
        self.client = mqtt.Client(
            CallbackAPIVersion.VERSION2,
            client_id=f"{interface}-{cfg.manufacturer}-{cfg.serial_number}",
            clean_session=True,
        )
        if broker.username is not None:
            self.client.username_pw_set(broker.username, broker.password)
        with self.lock:
            will = encode(wire.connection(vehicle, ConnectionState.CONNECTIONBROKEN))
        self.client.will_set(self.topic(TopicKind.CONNECTION), will, qos=1, retain=True)
        self.client.reconnect_delay_set(*RECONNECT_DELAY)
        self.client.on_connect = _guarded("connect", self._on_connect)
        self.client.on_disconnect = _guarded("disconnect", self._on_disconnect)
        self.client.on_message = _guarded("message", self._on_message)
        self.client.on_publish = _guarded("publish", self._on_publish)

    def topic(self, kind: TopicKind) -> str:
        """Full topic of this vehicle for ``kind``."""
        return str(self._topic.with_kind(kind))

    # ------------------------------------------------------------------ lifecycle
    def start(self) -> None:
        """Connect in the background; paho retries until the broker is reachable."""
        self.client.connect_async(self.broker.host, self.broker.port, self.broker.keepalive)
        self.client.loop_start()

    def stop(self, timeout: float = STOP_TIMEOUT_SECONDS) -> None:
        """Graceful stop: publish OFFLINE (retained), then DISCONNECT so no will is sent."""
        if self.client.is_connected():
            with self.lock:
                offline = encode(wire.connection(self.vehicle, ConnectionState.OFFLINE))
            info = self.client.publish(
                self.topic(TopicKind.CONNECTION), offline, qos=1, retain=True
            )
            try:
                info.wait_for_publish(timeout)
            except (RuntimeError, ValueError) as exc:
                log.warning("%s: OFFLINE not confirmed: %s", self.vehicle.config.serial_number, exc)
        self.client.disconnect()
        self.client.loop_stop()
        self.connected.clear()

    def break_connection(self, duration: float | None = None) -> None:
        """Fault injection: drop the TCP connection without DISCONNECT.

        The broker then publishes the last will (CONNECTIONBROKEN) and paho reconnects on
        its own, publishing ONLINE again, exactly like a real network outage. With
        ``duration`` (simulated seconds) the first reconnect attempt waits that long
        (whole wall seconds, at least 1); the usual back-off returns once connected.
        """
        if duration is not None:
            wall = max(1, math.ceil(duration / self.vehicle.config.time_scale))
            self.client.reconnect_delay_set(wall, max(wall, RECONNECT_DELAY[1]))
        log.info("%s: breaking the connection", self.vehicle.config.serial_number)
        sock = self.client.socket()
        if isinstance(sock, socket.socket):
            sock.shutdown(socket.SHUT_RDWR)

    # ------------------------------------------------------------------ paho callbacks
    def _on_connect(
        self,
        client: mqtt.Client,
        _userdata: object,
        _flags: mqtt.ConnectFlags,
        reason: ReasonCode,
        _properties: object,
    ) -> None:
        if reason.is_failure:
            log.warning("%s: connection refused: %s", self.vehicle.config.serial_number, reason)
            return
        # Subscribe before announcing ONLINE: the broker handles packets of one connection
        # in order, so an order sent in reaction to ONLINE cannot be missed.
        client.reconnect_delay_set(*RECONNECT_DELAY)  # undo a scripted longer outage
        client.subscribe([(topic, 0) for topic in self._inbound])
        with self.lock:
            online = encode(wire.connection(self.vehicle, ConnectionState.ONLINE))
            factsheet = encode(wire.factsheet(self.vehicle))
            self.vehicle.take_factsheet_due()
            self.vehicle.mark_state_due()
        # Factsheet first: once the broker acknowledges ONLINE it has processed the
        # factsheet too, so "connected" means both are retained on the broker.
        client.publish(self.topic(TopicKind.FACTSHEET), factsheet, qos=0, retain=True)
        info = client.publish(self.topic(TopicKind.CONNECTION), online, qos=1, retain=True)
        self._online_mid = info.mid
        self.flush()
        log.info("%s: connected", self.vehicle.config.serial_number)

    def _on_publish(
        self,
        _client: mqtt.Client,
        _userdata: object,
        mid: int,
        _reason: ReasonCode,
        _properties: object,
    ) -> None:
        if mid == self._online_mid:
            self.connected.set()

    def _on_disconnect(
        self,
        _client: mqtt.Client,
        _userdata: object,
        _flags: mqtt.DisconnectFlags,
        reason: ReasonCode,
        _properties: object,
    ) -> None:
        self.connected.clear()
        if reason.is_failure:
            serial = self.vehicle.config.serial_number
            log.warning("%s: connection lost (%s), reconnecting", serial, reason)

    def _on_message(self, _client: mqtt.Client, _userdata: object, msg: mqtt.MQTTMessage) -> None:
        kind = self._inbound.get(msg.topic)
        if kind is None:
            return
        serial = self.vehicle.config.serial_number
        if kind in (TopicKind.ZONE_SET, TopicKind.RESPONSES):
            self._on_zones(kind, bytes(msg.payload))
            return
        try:
            message = wire.decode_inbound(kind, msg.payload, self._version)
        except DecodeError as exc:
            log.warning("%s: undecodable %s: %s", serial, kind, exc)
            if kind is TopicKind.ORDER:
                with self.lock:
                    self.vehicle.reject_undecodable(str(exc))
                self.flush()
            return
        with self.lock:
            if isinstance(message, Order):
                accepted = self.vehicle.on_order(message)
                log.info(
                    "%s: order %s/%d %s",
                    serial,
                    message.order_id,
                    message.order_update_id,
                    "accepted" if accepted else "not accepted",
                )
            elif isinstance(message, InstantActions):
                self.vehicle.on_instant_actions(message)
        self.flush()

    def _on_zones(self, kind: TopicKind, payload: bytes) -> None:
        """3.0 zoneSet and responses (REFERENCE L.48-49), kept by simulator.maps."""
        try:
            message = decode(kind, payload, version=self._version)
        except DecodeError as exc:
            log.warning("%s: undecodable %s: %s", self.vehicle.config.serial_number, kind, exc)
            return
        with self.lock:
            if isinstance(message, v3.ZoneSet):
                self.vehicle.map_store.receive_zone_set(message.zone_set)
            elif isinstance(message, v3.Responses):
                self.vehicle.zone_requests.on_responses(message.responses)
            self.vehicle.mark_state_due()
        self.flush()

    # ------------------------------------------------------------------ publishing
    def flush(self) -> None:
        """Publish a state (and factsheet) now if an event made one due."""
        if not self.client.is_connected():
            return  # keep the flags set: on_connect publishes a fresh state anyway
        states: list[bytes] = []
        factsheet = None
        with self.lock:
            silent = self.silent or self.vehicle.silent
            if self.vehicle.take_state_due() and not silent:
                states = [encode(state) for state in wire.states(self.vehicle)]
            if self.vehicle.take_factsheet_due():
                factsheet = encode(wire.factsheet(self.vehicle))
        if factsheet is not None:
            self.client.publish(self.topic(TopicKind.FACTSHEET), factsheet, qos=0, retain=True)
        for payload in states:
            self._publish_state(payload)

    def _publish_state(self, payload: bytes) -> None:
        self._last_state = time.monotonic()
        self.client.publish(self.topic(TopicKind.STATE), payload, qos=0)

    def pump(self, dt: float, now: float) -> None:
        """Called by the tick loop: advance the simulation, publish what is due."""
        cfg = self.vehicle.config
        with self.lock:
            self.vehicle.tick(min(dt, _MAX_TICK_SECONDS))
            previous = self._last_state
            periodic = now - previous >= cfg.state_interval
            if periodic:
                self.vehicle.mark_state_due()
            outage = self.vehicle.saboteur.take_disconnect() if self.connected.is_set() else None
            silent = self.silent or self.vehicle.silent
        if outage is not None:
            self.break_connection(outage)
        self.flush()
        if periodic:
            # The periodic state keeps its nominal grid too: restarting the interval at each
            # send added a tick's lateness to every period (0.5 s became 0.55 s at 10 Hz, more
            # on a loaded machine). A state sent on an event still restarts it (`_publish_state`).
            self._last_state = _on_grid(previous, cfg.state_interval, now)
        hz = cfg.visualization_hz
        period = 1.0 / hz if hz > 0 else 0.0
        if hz > 0 and now - self._last_visualization >= period and not silent:
            if not self.client.is_connected():
                return
            # Keep the cadence on the nominal grid (ticks rarely land exactly on it), but
            # never try to catch up on messages missed during a stall.
            self._last_visualization = _on_grid(self._last_visualization, period, now)
            with self.lock:
                payload = encode(wire.visualization(self.vehicle))
            self.client.publish(self.topic(TopicKind.VISUALIZATION), payload, qos=0)
