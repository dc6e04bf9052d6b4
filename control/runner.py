"""Runs a Controller: the paho link to the broker and the periodic main loop."""

import logging
import queue
import threading
import time
from collections.abc import Callable
from typing import Any, Protocol, runtime_checkable

import paho.mqtt.client as mqtt
from django.db import connections

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
# What an `order.assigned` command may name, by payload key: the ids of transport orders
# (dispatch), of a battery charge session and of a maintenance move to a station.
ASSIGNED_KEYS = {"orders": "orders", "charge_session": "charge_sessions", "service_move": "moves"}


@runtime_checkable
class AssignedOrderStore(Protocol):
    """A store that reads the orders an `order.assigned` command names on their own (see
    control.persistence.DjangoStore.assigned_orders); without it every command costs the full
    re-read of all active orders."""

    def assigned_orders(
        self, *, orders: list[int], charge_sessions: list[int], moves: list[int]
    ) -> list[ActiveOrder]: ...


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
    """The main thread of `control`: commands, order sync, flushes and broadcasts on timers.

    Commands come in on a thread of their own (`_receive`), which starts the orders that
    `order.assigned` commands name at once, whatever the main thread is doing (a flush or a
    full sync of a large fleet takes a good part of a second), and hands every other command
    to the main thread.
    """

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
        self._commands: queue.Queue[dict[str, Any]] = queue.Queue()  # for the main thread
        self._receiving = threading.Event()
        # The last full read of the active orders (when it began, what it listed) and when
        # the next is due: see `_sync`.
        self._read: tuple[float, list[ActiveOrder]] | None = None
        self._read_due = 0.0

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
        self._receiving.set()
        receiver = threading.Thread(target=self._receive, name="control-commands", daemon=True)
        receiver.start()
        try:
            while not self._stop.is_set() and not self._lost():
                # Wait for commands until the next timer is due (at most the broadcast interval):
                # a command still wakes the loop at once, and an idle loop does not spin.
                wait = min(due.values()) - time.monotonic()
                commands = self._next_commands(min(max(wait, 0.01), 0.2))
                self._take_commands(commands, due)
                now = time.monotonic()
                if now >= due["SYNC_INTERVAL"]:
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
                    due["BROADCAST_INTERVAL"] = now + self._broadcast_pause(len(rows))
        finally:
            self._receiving.clear()
            receiver.join(timeout=5.0)
            if self._may_write():
                self._safely(self.controller.flush)
            self.link.stop()
            self.finished.set()
            logger.info("control stopped; counters: %s", dict(self.controller.counters))

    def _broadcast_pause(self, rows: int) -> float:
        """Seconds to the next broadcast: the interval, stretched so that the rows built per
        second stay within BROADCAST_ROWS_PER_S (a vehicle changes with each of its messages,
        so a short interval builds nearly a row per message)."""
        budget = self.intervals.get("BROADCAST_ROWS_PER_S") or 0.0
        interval: float = self.intervals["BROADCAST_INTERVAL"]
        return max(interval, rows / budget) if budget > 0 else interval

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

    def _receive(self) -> None:
        """The command thread: waits on the queue, starts the orders `order.assigned` commands
        name (read on their own, not every active order) and passes the rest to the main
        thread. The periodic full sync stays the safety net for a lost command."""
        store = self.controller.store
        try:
            while self._receiving.is_set():
                commands = self._safely(self.receive_commands, 0.2) or []
                named = assigned_jobs(commands)
                if isinstance(store, AssignedOrderStore) and (
                    not any(named.values()) or self._safely(self._start_assigned, store, named)
                ):  # else (no named reads, or they failed) the main thread's full sync does it
                    commands = [c for c in commands if not names_assigned(c)]
                for command in commands:
                    self._commands.put(command)
        finally:
            connections.close_all()  # this thread's own database connection

    def _next_commands(self, timeout: float) -> list[dict[str, Any]]:
        """Wait up to `timeout` s for what the command thread passes on; then take all."""
        try:
            commands = [self._commands.get(timeout=timeout)]
        except queue.Empty:
            return []
        while True:
            try:
                commands.append(self._commands.get_nowait())
            except queue.Empty:
                return commands

    def _take_commands(self, commands: list[dict[str, Any]], due: dict[str, float]) -> None:
        """Carry out `commands` (the main thread's part); any of them makes the full sync due
        now, as before."""
        for command in commands:
            self._safely(self.controller.execute, command)
        if any(str(c.get("kind", "")).startswith("maps.") for c in commands):
            self._safely(self._load_distribution)  # a release was distributed
        if commands:
            due["SYNC_INTERVAL"] = 0.0
            self._read_due = 0.0  # with a full read

    def _start_assigned(self, store: AssignedOrderStore, named: dict[str, list[int]]) -> bool:
        orders = store.assigned_orders(
            orders=named["orders"], charge_sessions=named["charge_sessions"], moves=named["moves"]
        )
        self._know_maps(orders)
        self.controller.start_orders(orders)
        self.controller.counters["orders_read_on_command"] += len(orders)
        return True

    def _sync(self) -> None:
        """Sync the orders (resends, held-back updates, cancellations) and let traffic re-time.

        The database's list of active orders is read again every ORDER_READ_INTERVAL and after
        any command; in between the last read is synced again. Orders an `order.assigned`
        command names are started by the command thread and kept by the driver until a read
        lists them; reading every order with its route every second was a sixth of the
        main loop with 1,000 vehicles (docs/LOAD.md)."""
        now = time.monotonic()
        if self._read is None or now >= self._read_due:
            # orders the command thread starts from `now` on may be missing from this read
            orders: list[ActiveOrder] = self.controller.store.active_orders()
            self._read = (now, orders)
            self._read_due = now + self.intervals.get("ORDER_READ_INTERVAL", 0.0)
            self._know_maps(orders)
        read_at, orders = self._read
        self.controller.sync(orders, read_at=read_at)

    def _know_maps(self, orders: list[ActiveOrder]) -> None:
        known = {o.map_id for o in orders}
        if not known <= self.controller.layouts.keys():
            self.controller.layouts = self.controller.store.load_layouts()  # a map was added

    def _safely(self, func: Callable[..., Any], *args: Any) -> Any:
        try:
            return func(*args)
        except Exception:  # the loop must survive a database or Redis outage
            logger.exception("%s failed", getattr(func, "__name__", func))
            time.sleep(0.5)
            return None


def names_assigned(command: dict[str, Any]) -> bool:
    """Whether `command` is an `order.assigned` naming at least one valid id."""
    return command.get("kind") == "order.assigned" and any(
        _ids(command.get(field)) for field in ASSIGNED_KEYS
    )


def assigned_jobs(commands: list[dict[str, Any]]) -> dict[str, list[int]]:
    """The ids the `order.assigned` commands among `commands` name, per ASSIGNED_KEYS value
    (other commands are left out: the main thread carries them out)."""
    named: dict[str, list[int]] = {key: [] for key in ASSIGNED_KEYS.values()}
    for command in filter(names_assigned, commands):
        for field, key in ASSIGNED_KEYS.items():
            named[key] += _ids(command.get(field))
    return named


def _ids(value: Any) -> list[int]:
    values = value if isinstance(value, list) else [value]
    return [v for v in values if isinstance(v, int) and not isinstance(v, bool)]
