"""Driving transport orders as VDA 5050 orders: start, adopt, extend the base, resend, cancel.

Works on the live model only (no MQTT, no database): the controller calls it under its lock and
hands the progress it collects to the flusher.
"""

import logging
import time
from collections.abc import Callable

import vda5050
from control.capabilities import sends_max_speed
from control.execution import (
    LayoutIndex,
    OrderExecution,
    Phase,
    Progress,
    Window,
    passed_index,
)
from control.live import LiveVehicle
from control.order_messages import (
    LoadJob,
    OrderLimits,
    build_order,
    extension_window,
    initial_window,
)
from control.ports import ActiveOrder
from control.publisher import ProtocolLimitError, Publisher
from control.session import Link
from control.traffic_link import TrafficLink
from orders import capability

logger = logging.getLogger(__name__)


class OrderDriver:
    """Everything `control` does to get assigned transport orders driven to their end."""

    RESEND_AFTER = 5.0  # seconds without confirmation before the same message goes again
    MAX_ATTEMPTS = 6  # sends of one message to an online vehicle before the order fails

    def __init__(
        self,
        publisher: Publisher,
        layouts: Callable[[], dict[str, LayoutIndex]],
        *,
        base_ahead: int | None = None,
        horizon: int | None = None,
        traffic: TrafficLink | None = None,
    ) -> None:
        self.publisher = publisher
        self.layouts = layouts
        self.base_ahead = base_ahead
        self.horizon = horizon  # unreleased nodes sent after the base; None = all
        # With traffic management the base reaches as far as traffic released (control/
        # traffic_link.py); without it `base_ahead` nodes ahead of the vehicle.
        self.traffic = traffic
        self.progress: list[Progress] = []
        self._orders: dict[int, ActiveOrder] = {}
        # Orders taken on their own (add_orders), with when: a full read that began before
        # one was taken may not list it yet, so the sync of that read keeps it.
        self._added: dict[int, tuple[float, ActiveOrder]] = {}
        # Orders that ended in memory; the database may list them as active until the next
        # flush, and sync must not adopt them again.
        self._ended: set[int] = set()

    def sync(
        self, vehicles: Callable[[int], LiveVehicle | None], orders: list[ActiveOrder]
    ) -> None:
        """Start, adopt, extend, resend or cancel the assigned orders read from the database."""
        self.begin_sync(orders)
        for order in orders:
            self.sync_order(vehicles, order)

    def begin_sync(self, orders: list[ActiveOrder], *, read_at: float | None = None) -> None:
        """The first part of `sync`: take the database's list (read from `read_at` on, as
        time.monotonic(); None: just now) and let traffic re-time."""
        if self.traffic is not None:
            self.traffic.ensure(self.layouts())
            self.traffic.tick(time.monotonic())  # re-timed and re-planned bases go out below
        self._orders = {o.transport_order_id: o for o in orders}
        since = time.monotonic() if read_at is None else read_at
        self._added = {pk: added for pk, added in self._added.items() if added[0] >= since}
        for pk, (_, order) in self._added.items():
            self._orders.setdefault(pk, order)  # taken after the read began: not in it yet
        self._ended &= self._orders.keys()  # forget what the database closed
        if self.traffic is not None:
            busy = {o.vehicle_pk for o in self._orders.values()}
            self.traffic.park_stale(busy, time.monotonic())

    def add_orders(self, orders: list[ActiveOrder]) -> None:
        """Take orders read on their own (named by an `order.assigned` command) next to those
        of the last sync, without the traffic re-timing of a full sync; `sync_order` follows.
        The next full read lists them too (see `_added` for one that began before)."""
        if self.traffic is not None:
            self.traffic.ensure(self.layouts())
        now = time.monotonic()
        for order in orders:
            self._orders[order.transport_order_id] = order
            self._added[order.transport_order_id] = (now, order)

    def sync_order(self, vehicles: Callable[[int], LiveVehicle | None], order: ActiveOrder) -> None:
        """The rest of `sync`, one order at a time (the controller may let go of its lock
        between two orders: starting one plans its route, which takes milliseconds)."""
        vehicle = vehicles(order.vehicle_pk)
        if vehicle is not None and order.transport_order_id not in self._ended:
            self._sync_one(vehicle, order)

    def on_state(self, vehicle: LiveVehicle, state: vda5050.State) -> None:
        """Follow the vehicle's progress on its order and release more of the route."""
        if self.traffic is not None:
            self.traffic.ensure(self.layouts())
            for other in self.traffic.observe(vehicle, state, time.monotonic()):
                self._extend_released(other)  # it waited for this vehicle
        execution = vehicle.execution
        if execution is None:
            return
        progress = execution.observe(state)
        fatal = execution.fatal_error(state)
        if fatal is not None:
            progress.append(fatal)
        failed = progress and any(p.kind == "failed" for p in progress)
        if failed and state.order_id == execution.vda_order_id:
            self.cancel(vehicle, execution)  # the vehicle keeps its order until cancelled (G.36)
        manual = execution.left_automatic(state)  # the vehicle cleared the order itself (G.37)
        if manual is not None:
            progress.append(manual)
        self.progress.extend(progress)
        if execution.phase is Phase.DONE:
            self._ended.add(execution.transport_order_id)
            vehicle.execution = None
            if self.traffic is not None:
                self.traffic.ended(vehicle, time.monotonic())
        elif execution.phase is Phase.RUNNING and not execution.awaiting_confirmation:
            order = self._orders.get(execution.transport_order_id)
            if order is not None:
                self._extend(vehicle, order, execution)

    def cancel(self, vehicle: LiveVehicle, execution: OrderExecution) -> None:
        """Send cancelOrder; the execution ends when the vehicle reports it finished (D.19)."""
        action_id = execution.start_cancel()
        self.publisher.instant_action(vehicle, "cancelOrder", action_id=action_id)

    def _sync_one(self, vehicle: LiveVehicle, order: ActiveOrder) -> None:
        execution = vehicle.execution
        if execution is not None and execution.transport_order_id != order.transport_order_id:
            return  # finishing another order; this one waits
        if execution is None:
            execution = self._start(vehicle, order)
            if execution is None:
                return
        if execution.phase not in {Phase.SENT, Phase.RUNNING}:
            return
        if order.cancel_requested:
            self.cancel(vehicle, execution)
        elif not execution.awaiting_confirmation:
            self._extend(vehicle, order, execution)  # e.g. one held back by minOrderInterval
        elif time.monotonic() - execution.sent_monotonic > self.RESEND_AFTER:
            self._resend(vehicle, order, execution)

    def _start(self, vehicle: LiveVehicle, order: ActiveOrder) -> OrderExecution | None:
        state = vehicle.state
        if state is None or order.map_id not in self.layouts():
            return None
        execution = OrderExecution.plan(
            transport_order_id=order.transport_order_id,
            vda_order_id=order.vda_order_id,
            route=order.route,
            pickup=order.pickup_node,
            kind=order.kind,
            steps=order.steps,
        )
        if state.order_id == order.vda_order_id:
            # Restarted mid-order: adopt, never resend. The base released before is what the
            # vehicle still lists (REFERENCE B.15: assume the base is driven).
            execution.released_until = _released_until(state)
            execution.update_id = execution.confirmed_update = state.order_update_id
            vehicle.execution = execution
            vehicle.needs_broadcast = True  # its live row names the transport order
            self.progress.extend(execution.observe(state))
            return execution
        if order.cancel_requested:
            self._end(Progress("cancelled", order.transport_order_id))
            return None
        if not (vehicle.is_available and vehicle.is_idle):
            return None
        if state.last_node_id != order.route[0]:
            reason = f"vehicle is at {state.last_node_id}, route starts at {order.route[0]}"
            self._end(Progress("requeued", order.transport_order_id, {"reason": reason}))
            return None
        window: Window | None = initial_window(len(order.route), self._limits(vehicle))
        if self.traffic is not None:
            limits = self._limits(vehicle)
            window = self.traffic.first_window(
                vehicle, execution, order.map_id, limits.max_nodes, limits.horizon
            )
        if window is None or not self._send(vehicle, order, execution, window, update_id=0):
            return None
        vehicle.execution = execution
        vehicle.needs_broadcast = True  # its live row names the transport order
        # From now on only the vehicle's state decides; the reconciler must not take it back.
        self.progress.append(Progress("sent", order.transport_order_id))
        return execution

    def _extend(self, vehicle: LiveVehicle, order: ActiveOrder, execution: OrderExecution) -> None:
        """Release more of the route with an order update stitched at the last base node."""
        state = vehicle.state
        if execution.fully_released or state is None or state.order_id != execution.vda_order_id:
            return
        if self.traffic is not None and self.traffic.controls(vehicle, execution.vda_order_id):
            limits = self._limits(vehicle)
            traffic_window = self.traffic.next_window(
                vehicle, execution, limits.max_nodes, limits.horizon
            )
            if traffic_window is not None:
                self._send(vehicle, order, execution, traffic_window, execution.update_id + 1)
            return
        if self.traffic is not None and self.traffic.lost(vehicle, execution.vda_order_id):
            return  # traffic plans it again once the vehicle waits at its decision point
        passed = passed_index(state)
        if state.new_base_request:
            passed = max(passed, execution.released_until)  # waiting at the decision point
        window = extension_window(
            len(execution.route), execution.released_until, passed, self._limits(vehicle)
        )
        if window is not None:
            self._send(vehicle, order, execution, window, update_id=execution.update_id + 1)

    def _extend_released(self, vehicle: LiveVehicle) -> None:
        """Send the base traffic released to a vehicle, if its order can take an update now."""
        execution = vehicle.execution
        order = self._orders.get(execution.transport_order_id) if execution else None
        if execution is None or order is None:
            return
        if execution.phase is Phase.RUNNING and not execution.awaiting_confirmation:
            self._extend(vehicle, order, execution)

    def _resend(self, vehicle: LiveVehicle, order: ActiveOrder, execution: OrderExecution) -> None:
        """Send the unconfirmed message again, identical (B.14), or give up after MAX_ATTEMPTS."""
        if vehicle.connection != Link.ONLINE or execution.window is None:
            return  # an unreachable vehicle gets no resends and no blame
        if execution.attempts >= self.MAX_ATTEMPTS:
            execution.phase = Phase.DONE
            vehicle.execution = None
            vehicle.needs_broadcast = True
            if self.traffic is not None:
                self.traffic.ended(vehicle, time.monotonic())
            reason = (
                f"vehicle did not confirm order {execution.vda_order_id} update "
                f"{execution.update_id} after {execution.attempts} attempts"
            )
            self._end(Progress("failed", order.transport_order_id, {"reason": reason}))
            return
        self._send(vehicle, order, execution, execution.window, execution.update_id, force=True)

    def _send(
        self,
        vehicle: LiveVehicle,
        order: ActiveOrder,
        execution: OrderExecution,
        window: Window,
        update_id: int,
        *,
        force: bool = False,
    ) -> bool:
        """Publish route window `window` as order update `update_id`, unless minOrderInterval
        (J.44) holds it back; a held-back message goes with a later state or sync."""
        now = time.monotonic()
        if not force and now - vehicle.last_order_sent < self._limits(vehicle).min_interval:
            return False
        job = LoadJob(order.load_id, order.load_type, order.pick_station, order.drop_station)
        nodes, edges = build_order(
            execution,
            self.layouts()[order.map_id],
            window,
            job,
            max_speed=sends_max_speed(vehicle.capabilities),
            loaded_speed=capability.loaded_speed(vehicle.factsheet, order.load_type),
        )
        try:
            self.publisher.order(
                vehicle,
                order_id=execution.vda_order_id,
                order_update_id=update_id,
                nodes=nodes,
                edges=edges,
            )
        except ProtocolLimitError as exc:
            self._refuse(vehicle, execution, str(exc))
            return False
        execution.sent(update_id, window)
        vehicle.last_order_sent = now
        return True

    def _refuse(self, vehicle: LiveVehicle, execution: OrderExecution, reason: str) -> None:
        """J.44: a message that breaks the vehicle's string limits is not sent; the order fails
        with the reason (a running one is cancelled: the vehicle drives only its base)."""
        detail = {"reason": f"not sent: {reason}"}
        self._end(Progress("failed", execution.transport_order_id, detail))
        if vehicle.execution is execution:
            self.cancel(vehicle, execution)

    def _limits(self, vehicle: LiveVehicle) -> OrderLimits:
        capabilities = vehicle.capabilities
        if capabilities is None:
            return OrderLimits(base_ahead=self.base_ahead, horizon=self.horizon)
        return OrderLimits(
            max_nodes=capabilities.max_order_nodes,
            base_ahead=self.base_ahead,
            min_interval=capabilities.min_order_interval,
            horizon=self.horizon,
        )

    def _end(self, progress: Progress) -> None:
        self.progress.append(progress)
        self._ended.add(progress.order_id)


def _released_until(state: vda5050.State) -> int:
    """The route index of the last base node the vehicle still lists (or has passed)."""
    released = [n.sequence_id for n in state.node_states if n.released]
    return max(released, default=state.last_node_sequence_id or 0) // 2
