"""Runs a Controller: the paho link to the broker and the periodic main loop."""

import logging
import threading
import time
from collections.abc import Callable
from typing import Any

import paho.mqtt.client as mqtt

from control import map_store
from control.controller import Controller
from control.leader import Leadership
from control.ports import ActiveOrder
from vda5050.enums import TopicKind

logger = logging.getLogger(__name__)

SUBSCRIBED = {
    TopicKind.STATE: 0,
    TopicKind.CONNECTION: 1,
    TopicKind.FACTSHEET: 0,
    TopicKind.VISUALIZATION: 0,
}


class MqttLink:
    """One paho client: subscribes to the vehicle topics and publishes for the controller."""

    def __init__(self, client: mqtt.Client, host: str, port: int, controller: Controller) -> None:
        self.client, self.host, self.port = client, host, port
        self.controller = controller
        self.connected = threading.Event()
        client.on_connect = self._on_connect
        client.on_disconnect = self._on_disconnect
        client.on_message = self._on_message
        controller.publisher.publish = self.publish

    def start(self) -> None:
        self.client.connect_async(self.host, self.port, keepalive=15)
        self.client.loop_start()

    def stop(self) -> None:
        self.client.disconnect()
        self.client.loop_stop()

    def publish(self, topic: str, payload: bytes, qos: int) -> None:
        result = self.client.publish(topic, payload, qos=qos)
        if result.rc != mqtt.MQTT_ERR_SUCCESS:
            logger.warning("publish to %s failed (rc=%s)", topic, result.rc)

    def _on_connect(
        self, client: mqtt.Client, userdata: Any, flags: Any, reason: Any, properties: Any
    ) -> None:
        if reason.is_failure:
            logger.error("broker refused the connection: %s", reason)
            return
        interface = self.controller.interface_name
        client.subscribe([(f"{interface}/+/+/+/{kind}", qos) for kind, qos in SUBSCRIBED.items()])
        logger.info("connected to %s:%s, subscribed to %s/+/+/+/…", self.host, self.port, interface)
        self.connected.set()

    def _on_disconnect(
        self, client: mqtt.Client, userdata: Any, flags: Any, reason: Any, properties: Any
    ) -> None:
        self.connected.clear()
        logger.warning("disconnected from broker (%s); paho reconnects", reason)

    def _on_message(self, client: mqtt.Client, userdata: Any, message: mqtt.MQTTMessage) -> None:
        self.controller.handle_message(message.topic, bytes(message.payload))


class ControlLoop:
    """The main thread of `control`: commands, order sync, flushes and broadcasts on timers."""

    def __init__(
        self,
        controller: Controller,
        link: MqttLink,
        *,
        receive_commands: Callable[[float], list[dict[str, Any]]],
        broadcast: Callable[[list[dict[str, Any]]], None],
        intervals: dict[str, float],
        stream_vehicle: Callable[[int, dict[str, Any]], None] | None = None,
    ) -> None:
        self.controller, self.link = controller, link
        self.receive_commands, self.broadcast = receive_commands, broadcast
        self.stream_vehicle = stream_vehicle  # raw messages to open vehicle pages
        self.intervals = intervals
        # Set by control.standby: the loop runs while this process leads and writes only
        # while its lease runs (a fenced-off leader must not overwrite the new leader's rows).
        self.leadership: Leadership | None = None
        self._stop = threading.Event()
        self.finished = threading.Event()  # set when run() has returned (helpers stop with it)
        self._layouts_revision: object = None

    def stop(self) -> None:
        """Ask the loop to finish; safe from a signal handler or another thread."""
        self._stop.set()

    def run(self) -> None:
        """Run until `stop()`; then flush what is left and disconnect cleanly."""
        self.controller.load()
        self.link.start()
        due = dict.fromkeys(
            ("SYNC_INTERVAL", "FLUSH_INTERVAL", "BROADCAST_INTERVAL", "REGISTRY_INTERVAL"), 0.0
        )
        try:
            while not self._stop.is_set() and not self._lost():
                # Wait for commands until the next timer is due (at most the broadcast interval):
                # a command still wakes the loop at once, and an idle loop does not spin.
                wait = min(due.values()) - time.monotonic()
                commands = self._safely(self.receive_commands, min(max(wait, 0.01), 0.2)) or []
                for command in commands:
                    self._safely(self.controller.execute, command)
                if any(str(c.get("kind", "")).startswith("maps.") for c in commands):
                    self._safely(self._load_distribution)  # a release was distributed
                now = time.monotonic()
                if commands or now >= due["SYNC_INTERVAL"]:
                    self._safely(self._sync)
                    due["SYNC_INTERVAL"] = now + self.intervals["SYNC_INTERVAL"]
                if now >= due["REGISTRY_INTERVAL"]:
                    self._safely(self._refresh_registry)
                    due["REGISTRY_INTERVAL"] = now + self.intervals.get("REGISTRY_INTERVAL", 10.0)
                if now >= due["FLUSH_INTERVAL"] and self._may_write():
                    self._safely(self.controller.flush)
                    self._safely(self._save_distribution)
                    due["FLUSH_INTERVAL"] = now + self.intervals["FLUSH_INTERVAL"]
                if now >= due["BROADCAST_INTERVAL"]:
                    rows = self.controller.collect_broadcast()
                    if rows:
                        self._safely(self.broadcast, rows)
                    if self.stream_vehicle is not None:
                        for pk, event in self._safely(self.controller.collect_watched) or []:
                            self._safely(self.stream_vehicle, pk, event)
                    due["BROADCAST_INTERVAL"] = now + self.intervals["BROADCAST_INTERVAL"]
        finally:
            if self._may_write():
                self._safely(self.controller.flush)
            self.link.stop()
            self.finished.set()
            logger.info("control stopped; counters: %s", dict(self.controller.counters))

    def _lost(self) -> bool:
        return self.leadership is not None and self.leadership.lost.is_set()

    def _may_write(self) -> bool:
        return self.leadership is None or self.leadership.holds_lease()

    def _refresh_registry(self) -> None:
        """Dialects from the vehicle registry; layouts again when one was edited."""
        store = self.controller.store
        self.controller.apply_dialects(store.vehicle_dialects())
        revision = store.layouts_revision()
        if revision != self._layouts_revision:
            if self._layouts_revision is not None:
                self.controller.layouts = store.load_layouts()
            self._layouts_revision = revision
        self._load_distribution()  # releases and zone sets (cheap: a few rows)

    def _load_distribution(self) -> None:
        targets, zone_sets = map_store.load_targets()
        with self.controller.lock:
            self.controller.distribution.set_targets(targets, zone_sets)

    def _save_distribution(self) -> None:
        with self.controller.lock:
            self.controller.distribution.tick()
            rows = self.controller.distribution.collect_statuses()
        try:
            map_store.save_map_statuses(rows)
        except Exception:
            with self.controller.lock:
                self.controller.distribution.requeue(rows)  # written with the next save
            raise

    def _sync(self) -> None:
        orders: list[ActiveOrder] = self.controller.store.active_orders()
        known = {o.map_id for o in orders}
        if not known <= self.controller.layouts.keys():
            self.controller.layouts = self.controller.store.load_layouts()  # a map was added
        self.controller.sync(orders)

    def _safely(self, func: Callable[..., Any], *args: Any) -> Any:
        try:
            return func(*args)
        except Exception:  # the loop must survive a database or Redis outage
            logger.exception("%s failed", getattr(func, "__name__", func))
            time.sleep(0.5)
            return None
