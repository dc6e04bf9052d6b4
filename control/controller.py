"""The master-control loop: VDA 5050 in and out, the live fleet model, order execution.

Hot path (paho's network thread): parse topic → decode → update the live model → track the
order → queue persistence and broadcast. No database and no Celery per message. The main thread
runs the periodic work: commands from web/Celery, sync with assigned orders, batched flushes and
throttled broadcasts. One lock keeps the model consistent between the two threads.
"""

import logging
import threading
import time
from collections import Counter
from collections.abc import Callable
from dataclasses import dataclass, field
from datetime import UTC, datetime
from typing import Any, Protocol

import vda5050
from control import snapshots
from control.execution import LayoutIndex, OrderExecution, Phase, Progress, build_order
from control.live import Fleet, LiveVehicle
from vda5050 import DecodeError, decode, encode
from vda5050.enums import TopicKind
from vda5050.headers import HeaderCounter, HeaderFields
from vda5050.topics import Topic, TopicError

logger = logging.getLogger(__name__)

Publish = Callable[[str, bytes, int], None]


@dataclass(frozen=True)
class ActiveOrder:
    """An assigned transport order as `control` needs it (read from the database by the store)."""

    transport_order_id: int
    vda_order_id: str
    vehicle_pk: int
    route: list[str]
    pickup_node: str
    map_id: str
    pick_station: str
    drop_station: str
    load_id: str = ""
    load_type: str = "EPAL"
    cancel_requested: bool = False


@dataclass
class FlushBatch:
    """What the flusher writes in one go."""

    new_vehicles: list[LiveVehicle] = field(default_factory=list)
    snapshots: list[dict[str, Any]] = field(default_factory=list)
    factsheets: dict[int, dict[str, Any]] = field(default_factory=dict)
    progress: list[Progress] = field(default_factory=list)
    newly_available: int = 0


class Store(Protocol):
    """The database side of `control` (see control.persistence.DjangoStore)."""

    def load_layouts(self) -> dict[str, LayoutIndex]: ...
    def load_vehicles(self) -> list[dict[str, Any]]: ...
    def active_orders(self) -> list[ActiveOrder]: ...
    def flush(self, batch: FlushBatch) -> dict[tuple[str, str], int]: ...
    def request_dispatch(self) -> None: ...


class Controller:
    """The live fleet and everything `control` decides; MQTT and the database are injected."""

    RESEND_AFTER = 5.0  # seconds without acceptance before an order is sent again

    def __init__(
        self, *, store: Store, interface_name: str, publish: Publish | None = None
    ) -> None:
        self.store = store
        self.interface_name = interface_name
        self.publish: Publish = publish or (lambda topic, payload, qos: None)
        self.fleet = Fleet()
        self.layouts: dict[str, LayoutIndex] = {}
        self.headers = HeaderCounter()
        self.counters: Counter[str] = Counter()
        self.lock = threading.RLock()
        self._progress: list[Progress] = []
        # Orders that ended in memory; the database may list them as active until the next
        # flush, and sync must not adopt them again.
        self._ended: set[int] = set()

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
                vehicle.needs_flush = False

    # Inbound: one handler per topic kind -------------------------------------------------------

    def handle_message(self, topic_text: str, payload: bytes) -> None:
        """Decode one MQTT message at the edge and apply it; bad input is logged and counted."""
        self.counters["messages"] += 1
        try:
            topic = Topic.parse(topic_text)
        except TopicError as exc:
            self._reject("bad_topic", topic_text, exc)
            return
        if topic.interface_name != self.interface_name:
            return
        handler = self._handlers.get(topic.kind)
        if handler is None:
            return  # our own order/instantActions echoes
        with self.lock:
            vehicle = self.fleet.get_or_add(
                topic.manufacturer, topic.serial_number, topic.interface_name
            )
            try:
                message = decode(topic.kind, payload, version=vehicle.version)
            except DecodeError as exc:
                vehicle.decode_errors += 1
                self._reject("decode_errors", topic_text, exc)
                return
            try:
                handler(self, vehicle, message)
            except Exception:  # one bad robot never stops the fleet
                self.counters["handler_errors"] += 1
                logger.exception("handler failed for %s", topic_text)

    def on_state(self, vehicle: LiveVehicle, state: vda5050.State) -> None:
        vehicle.apply_state(state, received_at=datetime.now(UTC))
        execution = vehicle.execution
        if execution is None:
            return
        progress = execution.observe(state)
        fatal = execution.fatal_error(state)
        if fatal is not None:
            progress.append(fatal)
        if any(p.kind == "failed" for p in progress) and state.order_id == execution.vda_order_id:
            self._send_cancel(vehicle, execution)  # the vehicle keeps its order until cancelled
        self._progress.extend(progress)
        if execution.phase is Phase.DONE:
            self._ended.add(execution.transport_order_id)
            vehicle.execution = None

    def on_connection(self, vehicle: LiveVehicle, message: vda5050.Connection) -> None:
        vehicle.apply_connection(message, received_at=datetime.now(UTC))

    def on_factsheet(self, vehicle: LiveVehicle, message: vda5050.Factsheet) -> None:
        vehicle.apply_factsheet(message)

    def on_visualization(self, vehicle: LiveVehicle, message: vda5050.Visualization) -> None:
        if message.agv_position is not None:
            vehicle.visual_position = message.agv_position
            vehicle.needs_broadcast = True

    _handlers: dict[str, Callable[["Controller", LiveVehicle, Any], None]] = {
        TopicKind.STATE: on_state,
        TopicKind.CONNECTION: on_connection,
        TopicKind.FACTSHEET: on_factsheet,
        TopicKind.VISUALIZATION: on_visualization,
    }

    def _reject(self, counter: str, topic_text: str, exc: Exception) -> None:
        self.counters[counter] += 1
        if self.counters[counter] <= 20 or self.counters[counter] % 1000 == 0:
            logger.warning(
                "dropped message on %s (%s #%d): %s",
                topic_text[:200],
                counter,
                self.counters[counter],
                exc,
            )

    # Outbound ----------------------------------------------------------------------------------

    def sync(self, orders: list[ActiveOrder]) -> None:
        """Start, adopt, resend or cancel the assigned orders read from the database."""
        with self.lock:
            self._ended &= {o.transport_order_id for o in orders}  # forget what the DB closed
            for order in orders:
                if order.transport_order_id in self._ended:
                    continue
                vehicle = self.fleet.by_pk(order.vehicle_pk)
                if vehicle is not None:
                    self._sync_one(vehicle, order)

    def _sync_one(self, vehicle: LiveVehicle, order: ActiveOrder) -> None:
        execution = vehicle.execution
        if execution is not None and execution.transport_order_id != order.transport_order_id:
            return  # finishing another order; this one waits
        if execution is None:
            execution = self._start(vehicle, order)
            if execution is None:
                return
        if order.cancel_requested and execution.phase in {Phase.SENT, Phase.RUNNING}:
            self._send_cancel(vehicle, execution)
        elif execution.phase is Phase.SENT and (
            time.monotonic() - execution.sent_monotonic > self.RESEND_AFTER
        ):
            self._publish_order(vehicle, order, execution)  # identical content: REFERENCE B.14

    def _start(self, vehicle: LiveVehicle, order: ActiveOrder) -> OrderExecution | None:
        state = vehicle.state
        if state is None or order.map_id not in self.layouts:
            return None
        execution = OrderExecution.plan(
            transport_order_id=order.transport_order_id,
            vda_order_id=order.vda_order_id,
            route=order.route,
            pickup=order.pickup_node,
        )
        if state.order_id == order.vda_order_id:
            vehicle.execution = execution  # restarted mid-order: adopt, never resend
            self._progress.extend(execution.observe(state))
            return execution
        if order.cancel_requested:
            self._end(Progress("cancelled", order.transport_order_id))
            return None
        if not (vehicle.is_available and vehicle.is_idle):
            return None
        if state.last_node_id != order.route[0]:
            self._end(
                Progress(
                    "requeued",
                    order.transport_order_id,
                    {
                        "reason": f"vehicle is at {state.last_node_id}, "
                        f"route starts at {order.route[0]}"
                    },
                )
            )
            return None
        vehicle.execution = execution
        self._publish_order(vehicle, order, execution)
        return execution

    def _end(self, progress: Progress) -> None:
        self._progress.append(progress)
        self._ended.add(progress.order_id)

    def _publish_order(
        self, vehicle: LiveVehicle, order: ActiveOrder, execution: OrderExecution
    ) -> None:
        nodes, edges = build_order(
            execution,
            self.layouts[order.map_id],
            load_id=order.load_id,
            load_type=order.load_type,
            pick_station=order.pick_station,
            drop_station=order.drop_station,
        )
        message = vda5050.Order(
            **self._header(vehicle, TopicKind.ORDER),
            order_id=execution.vda_order_id,
            order_update_id=0,
            nodes=nodes,
            edges=edges,
        )
        self._send(vehicle, TopicKind.ORDER, message)
        execution.sent_monotonic = time.monotonic()

    def _send_cancel(self, vehicle: LiveVehicle, execution: OrderExecution) -> None:
        action_id = execution.start_cancel()
        self.send_instant_action(vehicle, "cancelOrder", action_id=action_id)

    def send_instant_action(
        self,
        vehicle: LiveVehicle,
        action_type: str,
        *,
        action_id: str | None = None,
        parameters: dict[str, Any] | None = None,
    ) -> str:
        """Publish one instant action to `vehicle`; returns its actionId."""
        action = vda5050.make_action(action_type, parameters, action_id=action_id)
        message = vda5050.InstantActions(
            **self._header(vehicle, TopicKind.INSTANT_ACTIONS), actions=[action]
        )
        self._send(vehicle, TopicKind.INSTANT_ACTIONS, message)
        return action.action_id

    def _header(self, vehicle: LiveVehicle, kind: TopicKind) -> HeaderFields:
        return self.headers.header(
            vehicle.manufacturer, vehicle.serial_number, kind, vehicle.version
        )

    def _send(self, vehicle: LiveVehicle, kind: TopicKind, message: Any) -> None:
        topic = Topic(
            interface_name=vehicle.interface_name,
            major_version=vda5050.major_version_of(vehicle.version),
            manufacturer=vehicle.manufacturer,
            serial_number=vehicle.serial_number,
            kind=kind,
        )
        self.publish(str(topic), encode(message), 0)
        self.counters[f"sent_{kind}"] += 1

    # Periodic: flush and broadcast --------------------------------------------------------------

    def collect_flush(self) -> FlushBatch:
        """Take what changed since the last flush (under the lock, without I/O)."""
        batch = FlushBatch()
        with self.lock:
            batch.progress, self._progress = self._progress, []
            for vehicle in self.fleet.vehicles.values():
                available = vehicle.is_available and vehicle.is_idle
                if available and not vehicle.was_available:
                    batch.newly_available += 1
                vehicle.was_available = available
                if not vehicle.needs_flush:
                    continue
                vehicle.needs_flush = False
                if vehicle.pk is None:
                    batch.new_vehicles.append(vehicle)
                    continue
                batch.snapshots.append(snapshots.row(vehicle))
                if vehicle.factsheet_changed and vehicle.factsheet is not None:
                    batch.factsheets[vehicle.pk] = vehicle.factsheet
                    vehicle.factsheet_changed = False
        return batch

    def flush(self) -> None:
        """Write one batch; on a database error the batch is put back and retried next time."""
        batch = self.collect_flush()
        if not (batch.new_vehicles or batch.snapshots or batch.progress or batch.factsheets):
            return
        try:
            registered = self.store.flush(batch)
        except Exception:
            logger.exception("flush failed; will retry")
            self._requeue(batch)
            return
        with self.lock:
            for vehicle in batch.new_vehicles:
                self.fleet.set_pk(vehicle, registered.get(vehicle.key))
                vehicle.needs_flush = True  # its snapshot goes with the next flush
        if batch.newly_available or batch.new_vehicles:
            self.store.request_dispatch()

    def _requeue(self, batch: FlushBatch) -> None:
        with self.lock:
            self._progress[:0] = batch.progress
            for vehicle in self.fleet.vehicles.values():
                if vehicle.pk is None or vehicle.pk in {s["pk"] for s in batch.snapshots}:
                    vehicle.needs_flush = True
                if vehicle.pk in batch.factsheets:
                    vehicle.factsheet_changed = True

    def collect_broadcast(self) -> list[dict[str, Any]]:
        """Browser rows of the vehicles that changed since the last broadcast."""
        with self.lock:
            changed = [v for v in self.fleet.vehicles.values() if v.needs_broadcast]
            for vehicle in changed:
                vehicle.needs_broadcast = False
            return [snapshots.browser_row(v, self.layouts) for v in changed]

    def all_browser_rows(self) -> list[dict[str, Any]]:
        with self.lock:
            return [snapshots.browser_row(v, self.layouts) for v in self.fleet.vehicles.values()]
