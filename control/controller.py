"""The master-control loop: VDA 5050 in and out, the live fleet model, order execution.

Hot path (paho's network thread): parse topic → decode → update the live model → track the
order → queue persistence and broadcast. No database and no Celery per message. The main thread
runs the periodic work: commands from web/Celery, sync with assigned orders, batched flushes and
throttled broadcasts. One lock keeps the model consistent between the two threads.
"""

import logging
import threading
import time
import uuid
from collections import Counter
from collections.abc import Callable
from datetime import UTC, datetime
from typing import Any

import vda5050
from control.action_states import ActionStatePolicy
from control.capabilities import refuse_instant_action
from control.conflicts import refuse_conflict
from control.distribution import Distribution
from control.driver import OrderDriver
from control.execution import LayoutIndex
from control.live import Fleet, InstantActionTrack, LiveVehicle
from control.message_log import IN, MessageLog
from control.periodic import PeriodicWork
from control.ports import ActiveOrder, Store
from control.publisher import ProtocolLimitError, Publish, Publisher
from control.session import PROBE_AFTER, PROBE_GRACE, Verdict
from control.traffic_link import TrafficLink
from control.versions import to_model, wire_version
from control.wait_log import WaitLog
from vda5050 import DecodeError, decode
from vda5050.enums import TopicKind
from vda5050.topics import Topic, TopicError

logger = logging.getLogger(__name__)

TOPIC_CACHE_SIZE = 20_000  # parsed topics kept: 4 inbound kinds for 5,000 vehicles
SLOW_SYNC_STEP = 0.002  # s: an order whose sync took longer (it was planned) ...
HAND_OVER = 0.0005  # s: ... is followed by this sleep, so waiting messages take the lock


_VEHICLE_COMMANDS: dict[str, tuple[str, dict[str, Any]]] = {
    "vehicle.pause": ("startPause", {}),
    "vehicle.resume": ("stopPause", {}),
}


# Commands control knows but cannot carry out yet: refused with the reason, never dropped.
_NOT_YET: dict[str, str] = {}


class Controller(PeriodicWork):
    """The live fleet and everything `control` decides; MQTT and the database are injected."""

    def __init__(
        self,
        *,
        store: Store,
        interface_name: str,
        publish: Publish | None = None,
        base_ahead: int | None = None,
        horizon: int | None = None,
        traffic: bool = False,
        park_idle: bool = True,
        park_after: float = 0.0,
        liveness_probe_after: float = PROBE_AFTER,
        liveness_probe_grace: float = PROBE_GRACE,
        motion_flush_interval: float = 0.0,
    ) -> None:
        self.store = store
        self.interface_name = interface_name
        self.fleet = Fleet()
        # A vehicle silent this long gets one stateRequest (0 = never; control.session).
        self.probe_after, self.probe_grace = liveness_probe_after, liveness_probe_grace
        # A snapshot whose only change is motion is written at most this often (seconds).
        self.motion_flush_interval = motion_flush_interval
        self.layouts: dict[str, LayoutIndex] = {}
        self.counters: Counter[str] = Counter()
        self._topics: dict[str, Topic] = {}  # topic text -> parsed (see _parse_topic)
        # Raw messages both ways for the vehicle page (control.message_log; watched ones stream).
        self.messages = MessageLog()
        self.publisher = Publisher(publish, self.counters, messages=self.messages)
        self.lock = threading.RLock()
        self._unflushed_outcomes: list[InstantActionTrack] = []  # from a failed flush
        self._job_requests: list[dict[str, Any]] = []  # the flush opens charge sessions, moves
        # Traffic management releases bases; off: a fixed `base_ahead` (single-vehicle sites).
        # `park_idle`: idle vehicles in the way of an order are sent to park (control/parking.py),
        # and with `park_after` > 0 those idle that long off a park station too.
        park = (lambda job: self._job_requests.append(job)) if park_idle else None
        fleet = lambda: list(self.fleet.vehicles.values())  # noqa: E731
        self.traffic = (
            TrafficLink(fleet, park=park, park_after=park_after, lock=self.lock)
            if traffic
            else None
        )
        self.waits = WaitLog()  # traffic waits as episodes, for the reports (control.wait_log)
        self.driver = OrderDriver(
            self.publisher,
            lambda: self.layouts,
            base_ahead=base_ahead,
            horizon=horizon,
            traffic=self.traffic,
        )
        self.action_states = ActionStatePolicy(self.publisher)  # 3.0 retries, clearing (E.27-28)
        # Map releases (K), 3.0 zone sets and zone/edge requests (L): control.distribution.
        self.distribution = Distribution(self.publisher, self.fleet, self.request_instant_action)

    def load(self) -> None:
        """Rebuild from the database: layouts and known vehicles (their state comes over MQTT)."""
        self.layouts = self.store.load_layouts()
        with self.lock:
            for row in self.store.load_vehicles():
                vehicle = self.fleet.get_or_add(
                    row["manufacturer"], row["serial_number"], row["interface_name"]
                )
                self.fleet.set_pk(vehicle, row["pk"])
                vehicle.version = row["protocol_version"]
                vehicle.dialect = row.get("dialect", "STANDARD")
                vehicle.needs_flush = False

    # Inbound: one handler per topic kind -------------------------------------------------------

    def handle_message(self, topic_text: str, payload: bytes) -> None:
        """Decode one MQTT message at the edge and apply it; bad input is logged and counted.

        Dropped: bad topics, undecodable payloads, payloads whose identity differs from their
        topic, and (except `connection`, whose last-will header is stale by design) duplicate
        or older header ids of the same connection.
        """
        self.counters["messages"] += 1
        try:
            topic = self._topics.get(topic_text) or self._parse_topic(topic_text)
        except TopicError as exc:
            self._reject("bad_topic", topic_text, exc)
            return
        if topic.interface_name != self.interface_name:
            return
        handler = self._handlers.get(topic.kind)
        if handler is None:
            return  # our own order/instantActions echoes
        with self.lock:
            # Only a valid message registers a vehicle: garbage on made-up serial numbers
            # must not fill the registry.
            known = self.fleet.vehicles.get((topic.manufacturer, topic.serial_number))
            version = wire_version(topic.major_version, known.version if known else None)
            try:
                raw = decode(topic.kind, payload, version=version)
                message = to_model(topic.kind, raw)
            except DecodeError as exc:
                if known is not None:
                    self.messages.record(known.key, IN, topic.kind, payload, note=str(exc)[:200])
                self._reject("decode_errors", topic_text, exc, known)
                return
            if (message.manufacturer, message.serial_number) != (
                topic.manufacturer,
                topic.serial_number,
            ):
                reason = f"payload is from {message.manufacturer}/{message.serial_number}"
                self._reject("identity_mismatch", topic_text, ValueError(reason), known)
                return
            vehicle = known or self.fleet.get_or_add(
                topic.manufacturer, topic.serial_number, topic.interface_name
            )
            self.messages.record(vehicle.key, IN, topic.kind, payload)
            if topic.kind != TopicKind.CONNECTION and message.header_id is not None:
                verdict = vehicle.session.check_header(topic.kind, message.header_id)
                if verdict is not Verdict.APPLY:
                    self.counters[verdict.value] += 1
                    vehicle.needs_flush = True  # the counters are shown
                    return
            try:
                handler(self, vehicle, message)
                if topic.kind == TopicKind.FACTSHEET and raw is not message:
                    vehicle.keep_battery_charging(raw)  # 3.0 only: adapted away otherwise
                self.distribution.after_message(vehicle, topic.kind, raw)
            except Exception:  # one bad robot never stops the fleet
                self.counters["handler_errors"] += 1
                logger.exception("handler failed for %s", topic_text)

    def clock_skew_of(self, topic_text: str) -> float | None:
        """The clock skew of the vehicle a handled message's topic names (None if unknown):
        right after a state, that state's age when applied."""
        topic = self._topics.get(topic_text)
        vehicle = (
            self.fleet.vehicles.get((topic.manufacturer, topic.serial_number)) if topic else None
        )
        return vehicle.session.clock_skew if vehicle is not None else None

    def _parse_topic(self, topic_text: str) -> Topic:
        """Parse and remember a valid topic: a fleet has a few topics per vehicle, and parsing
        (five levels checked by regex) was a third of the cost of a state message."""
        topic = Topic.parse(topic_text)
        if len(self._topics) >= TOPIC_CACHE_SIZE:
            self._topics.clear()  # made-up valid topics must not grow it without bound
        self._topics[topic_text] = topic
        return topic

    def on_state(self, vehicle: LiveVehicle, state: vda5050.State) -> None:
        if vehicle.apply_state(state, received_at=datetime.now(UTC)):
            self._reconcile(vehicle, reconnected=False)
        self.driver.on_state(vehicle, state)
        self.action_states.on_state(vehicle, state)

    def on_connection(self, vehicle: LiveVehicle, message: vda5050.Connection) -> None:
        if vehicle.apply_connection(message, received_at=datetime.now(UTC)):
            self._reconcile(vehicle, reconnected=True)

    def on_factsheet(self, vehicle: LiveVehicle, message: vda5050.Factsheet) -> None:
        vehicle.apply_factsheet(message)

    def on_visualization(self, vehicle: LiveVehicle, message: vda5050.Visualization) -> None:
        if message.agv_position is not None:
            vehicle.apply_pose(message.agv_position)

    def _reconcile(self, vehicle: LiveVehicle, *, reconnected: bool) -> None:
        """After a (re)connection ask for the current state and factsheet (REFERENCE H.38, J);
        after a first or late state only fetch a factsheet we do not have yet."""
        if reconnected:
            self.publisher.instant_action(vehicle, "stateRequest")
        if reconnected or (vehicle.factsheet is None and not vehicle.factsheet_requested):
            self.publisher.instant_action(vehicle, "factsheetRequest")
            vehicle.factsheet_requested = True

    _handlers: dict[str, Callable[["Controller", LiveVehicle, Any], None]] = {
        TopicKind.STATE: on_state,
        TopicKind.CONNECTION: on_connection,
        TopicKind.FACTSHEET: on_factsheet,
        TopicKind.VISUALIZATION: on_visualization,
    }

    def _reject(
        self, counter: str, topic_text: str, exc: Exception, vehicle: LiveVehicle | None = None
    ) -> None:
        self.counters[counter] += 1
        if vehicle is not None:
            vehicle.session.counters[counter] += 1
            vehicle.needs_flush = True
        if self.counters[counter] <= 20 or self.counters[counter] % 1000 == 0:
            logger.warning(
                "dropped message on %s (%s #%d): %s",
                topic_text[:200],
                counter,
                self.counters[counter],
                exc,
            )

    # Outbound ----------------------------------------------------------------------------------

    def apply_dialects(self, dialects: dict[int, str]) -> None:
        """Take the registry's dialect per vehicle (non-standard ones; others are standard)."""
        with self.lock:
            for vehicle in self.fleet.vehicles.values():
                vehicle.dialect = dialects.get(vehicle.pk or -1, "STANDARD")

    def sync(self, orders: list[ActiveOrder], *, read_at: float | None = None) -> None:
        """Start, adopt, extend, resend or cancel the assigned orders read from the database
        (the read began at `read_at`, time.monotonic(); None: just now).

        The lock is taken per order, not for the whole list: starting an order plans its route
        (milliseconds, more in congestion), and state messages must not wait for a dozen of
        them. After a slow one the loop sleeps a moment so that the waiting paho thread really
        gets the lock (a released lock is usually taken again at once by the thread that let
        it go)."""
        with self.lock:
            ready = self.distribution.ready_orders(orders)
            self.driver.begin_sync(ready, read_at=read_at)
        self._sync_each(ready)

    def start_orders(self, orders: list[ActiveOrder]) -> None:
        """Start the orders an `order.assigned` command names, read on their own, without
        waiting for the next full `sync` (which still follows and covers them as any other).

        The same steps and guarantees as `sync`: a vehicle busy with another order or not
        available leaves its order to a later sync, an order that ended in memory is not
        started again, and every publish is checked against the lease (Publisher). Safe from
        another thread than the one that syncs (control's command thread)."""
        with self.lock:
            ready = self.distribution.ready_orders(orders)
            self.driver.add_orders(ready)
        self._sync_each(ready)

    def _sync_each(self, orders: list[ActiveOrder]) -> None:
        for order in orders:
            started = time.perf_counter()
            with self.lock:
                self.driver.sync_order(self.fleet.by_pk, order)
            if time.perf_counter() - started > SLOW_SYNC_STEP:
                time.sleep(HAND_OVER)

    def execute(self, command: dict[str, Any]) -> None:
        """Carry out a command from web or Celery (fleet.control_queue).

        Order commands only wake the loop (the database says what to do, read by `sync`);
        vehicle commands become instant actions, checked against the vehicle's mode and
        factsheet first and tracked to their end.
        """
        kind = command.get("kind", "")
        if kind.startswith(("order.", "maps.")):
            return  # the loop re-reads orders (and, for maps., releases) from the database
        if kind == "vehicle.watch":  # a vehicle page is open: stream its raw messages
            self.watch_vehicle(command)
            return
        action_type, parameters = _VEHICLE_COMMANDS.get(kind, (None, {}))
        if kind == "vehicle.instant_action":
            action_type, parameters = command.get("action_type"), command.get("parameters") or {}
        request = command.get("command", command.get("request"))
        if kind in {"vehicle.charge", "vehicle.park"}:  # jobs the flush opens, driven like orders
            with self.lock:
                self._job_requests.append(command)
            return
        with self.lock:
            vehicle = self.fleet.by_pk(command.get("vehicle", -1))
            if vehicle is not None and kind in _NOT_YET:
                self.counters["refused_actions"] += 1
                vehicle.track(
                    InstantActionTrack(
                        f"refused-{uuid.uuid4()}",
                        kind,
                        "REFUSED",
                        reason=_NOT_YET[kind],
                        request=None if request is None else str(request),
                    )
                )
                return
            if vehicle is None or not isinstance(action_type, str):
                self.counters["bad_commands"] += 1
                logger.warning("ignored command %r: unknown vehicle or kind", command)
                return
            self.request_instant_action(
                vehicle,
                action_type,
                parameters,
                request=None if request is None else str(request),
            )

    def request_instant_action(
        self,
        vehicle: LiveVehicle,
        action_type: str,
        parameters: dict[str, Any],
        *,
        request: str | None = None,
    ) -> InstantActionTrack:
        """Send an operator's instant action if the vehicle may take it, and track it."""
        state = vehicle.state
        mode = str(state.operating_mode) if state is not None else None
        reason = refuse_instant_action(vehicle.capabilities, mode, action_type, parameters)
        if reason is None:  # E.23: nor may it conflict with the order or the vehicle's state
            execution = vehicle.execution
            reason = refuse_conflict(
                action_type,
                parameters,
                state,
                controlled_order=None if execution is None else execution.vda_order_id,
            )
        if reason is None:
            try:
                action_id = self.publisher.instant_action(
                    vehicle, action_type, parameters=parameters
                )
            except ProtocolLimitError as exc:  # J.44
                reason = str(exc)
        if reason is None:
            track = InstantActionTrack(action_id, action_type, "SENT", request=request)
        else:
            self.counters["refused_actions"] += 1
            track = InstantActionTrack(
                f"refused-{uuid.uuid4()}", action_type, "REFUSED", reason=reason, request=request
            )
        vehicle.track(track)
        return track
