"""Runtime of a :class:`~simulator.misbehaviour.Misbehaviour`: counters, timers, held states.

The vehicle asks its saboteur at each decision point (an order arrives, an action ends, a
state is built, time advances). Time is the vehicle's simulated clock, so unit tests drive
every misbehaviour with a fake clock. Every misbehaviour logs at INFO when it fires.
"""

from __future__ import annotations

import logging
import random
from datetime import UTC, datetime, timedelta
from typing import TYPE_CHECKING, TypeVar

import msgspec

from simulator.misbehaviour import Misbehaviour
from vda5050 import Order, State, v3
from vda5050.enums import OperatingMode
from vda5050.headers import format_timestamp

if TYPE_CHECKING:
    from simulator.vehicle import VirtualVehicle

log = logging.getLogger("simulator.misbehaviour")

_EPS = 1e-6

#: A state message of either protocol version (shaped alike: header, timestamp).
S = TypeVar("S", State, v3.State)


def _take(budget: int | None) -> tuple[bool, int | None]:
    """Use one unit of a budget (None = unlimited): (allowed, remaining budget)."""
    if budget is None:
        return True, None
    if budget <= 0:
        return False, 0
    return True, budget - 1


class Saboteur:
    """Carries out one vehicle's misbehaviour."""

    def __init__(self, vehicle: VirtualVehicle, plan: Misbehaviour) -> None:
        self.plan = plan
        self._vehicle = vehicle
        self._serial = vehicle.config.serial_number
        start = vehicle.sim_time
        seed: int | str = plan.seed if plan.seed is not None else self._serial
        self._rng = random.Random(seed)
        self._rejections = plan.reject_count
        self._drops = plan.drop_orders
        self._failures = plan.fail_count
        self._deferred: list[tuple[float, Order]] = []
        self._held: State | v3.State | None = None
        self._nodes = 0
        self._fatal_fired = False
        self._silence = (
            (start + plan.silent_at, start + plan.silent_at + plan.silent_for)
            if plan.silent_for > 0
            else None
        )
        self._was_silent = False
        self._disconnect_time = start + plan.disconnect_at if plan.disconnect_for > 0 else None
        self._disconnect_request: float | None = None
        self._mode_enter = start + plan.mode_at if plan.mode is not None else None
        self._mode_leave: float | None = None
        self._mode_before: OperatingMode | None = None
        if plan.active:
            log.info("%s: misbehaviour set: %s", self._serial, plan)

    def _fired(self, what: str, *args: object) -> None:
        log.info("%s: misbehaviour " + what, self._serial, *args)

    def adopt(self, previous: Saboteur) -> None:
        """Take over what the previous saboteur still holds (deferred orders, a held
        state) and leave a mode it entered, so replacing a misbehaviour loses nothing."""
        self._deferred = previous._deferred
        self._held = previous._held
        if previous._mode_before is not None:
            self._vehicle.set_operating_mode(previous._mode_before)

    # ------------------------------------------------------------------ orders
    def drop_order(self, order: Order) -> bool:
        """True if this order message is to be ignored entirely (``drop_orders``)."""
        if self._drops <= 0:
            return False
        self._drops -= 1
        self._fired(
            "drop_orders: ignoring order %s/%d (%d more to drop)",
            order.order_id,
            order.order_update_id,
            self._drops,
        )
        return True

    def rejection(self, order: Order) -> str | None:
        """The errorType to reject this order with (``reject_orders``), or None."""
        if self.plan.reject_orders is None:
            return None
        allowed, self._rejections = _take(self._rejections)
        if not allowed:
            return None
        self._fired(
            "reject_orders: rejecting order %s/%d with %s",
            order.order_id,
            order.order_update_id,
            self.plan.reject_orders,
        )
        return self.plan.reject_orders

    def defer(self, order: Order) -> bool:
        """Queue the order for ``delay_orders`` seconds; False if there is no delay."""
        if self.plan.delay_orders <= 0:
            return False
        due = self._vehicle.sim_time + self.plan.delay_orders
        self._deferred.append((due, order))
        self._fired(
            "delay_orders: order %s/%d waits %g s",
            order.order_id,
            order.order_update_id,
            self.plan.delay_orders,
        )
        return True

    def is_deferred(self, order: Order) -> bool:
        """True if the same (orderId, orderUpdateId) already waits in the queue."""
        key = (order.order_id, order.order_update_id)
        return any((o.order_id, o.order_update_id) == key for _, o in self._deferred)

    def due_orders(self) -> list[Order]:
        """Deferred orders whose delay is over, in arrival order."""
        now = self._vehicle.sim_time + _EPS
        due = [order for time, order in self._deferred if time <= now]
        self._deferred = [(time, order) for time, order in self._deferred if time > now]
        for order in due:
            self._fired(
                "delay_orders: processing order %s/%d", order.order_id, order.order_update_id
            )
        return due

    # ------------------------------------------------------------------ actions and nodes
    def action_fails(self, action_type: str) -> bool:
        """True if an action of this type must end FAILED (``fail_actions``)."""
        if action_type not in self.plan.fail_actions:
            return False
        allowed, self._failures = _take(self._failures)
        if allowed:
            self._fired("fail_actions: %s fails", action_type)
        return allowed

    def node_passed(self) -> None:
        """The vehicle traversed a node (counts towards ``fatal_after_nodes``)."""
        self._nodes += 1

    def fatal_due(self) -> bool:
        """True once, on the edge after the ``fatal_after_nodes``-th node, while driving."""
        limit = self.plan.fatal_after_nodes
        vehicle = self._vehicle
        if limit is None or self._fatal_fired or self._nodes < limit:
            return False
        if not (vehicle.driving and vehicle.distance_since_last_node > _EPS):
            return False
        self._fatal_fired = True
        self._fired(
            "fatal_after_nodes: FATAL %s after %d nodes", self.plan.fatal_error, self._nodes
        )
        return True

    # ------------------------------------------------------------------ time
    def advance(self) -> None:
        """Start and end timed episodes (silence, disconnect, operating mode)."""
        now = self._vehicle.sim_time + _EPS
        silent = self.silent
        if silent != self._was_silent:
            self._was_silent = silent
            self._fired("silent: %s", "publishing nothing" if silent else "publishing again")
            if not silent:
                self._vehicle.mark_state_due()
        if self._disconnect_time is not None and now >= self._disconnect_time:
            self._disconnect_time = None
            self._disconnect_request = self.plan.disconnect_for
            self._fired("disconnect: dropping the connection for %g s", self.plan.disconnect_for)
        if self._mode_enter is not None and now >= self._mode_enter and self.plan.mode:
            self._mode_enter = None
            self._mode_before = self._vehicle.operating_mode
            self._fired("mode: entering %s", self.plan.mode)
            self._vehicle.set_operating_mode(self.plan.mode)
            if self.plan.mode_for is not None:
                self._mode_leave = self._vehicle.sim_time + self.plan.mode_for
        if self._mode_leave is not None and now >= self._mode_leave and self._mode_before:
            self._fired("mode: back to %s", self._mode_before)
            self._vehicle.set_operating_mode(self._mode_before)
            self._mode_leave = self._mode_before = None

    @property
    def silent(self) -> bool:
        """True while a silence episode runs: no state and no visualization."""
        if self._silence is None:
            return False
        start, end = self._silence
        return start <= self._vehicle.sim_time + _EPS < end

    def silence(self, duration: float) -> None:
        """Be silent from now on for ``duration`` seconds (``set_silent(..., duration=)``)."""
        now = self._vehicle.sim_time
        self._silence = (now, now + duration) if duration > 0 else None
        self.advance()

    def take_disconnect(self) -> float | None:
        """Seconds to stay disconnected if a disconnect episode just began (once)."""
        request, self._disconnect_request = self._disconnect_request, None
        return request

    # ------------------------------------------------------------------ states
    def shape_states(self, state: S) -> list[S]:
        """The states to publish for one built state: held back, stale, duplicated.

        A vehicle builds states of one version only, so a held state has the same type.
        """
        plan = self.plan
        if self._held is None and self._chance(plan.reorder_states):
            self._held = state
            self._vehicle.mark_state_due()  # the newer state that overtakes it comes next
            self._fired("reorder_states: holding back state %d", state.header_id)
            return []
        if self._chance(plan.stale_states):
            stamp = datetime.now(UTC) - timedelta(seconds=plan.stale_age)
            state = msgspec.structs.replace(state, timestamp=format_timestamp(stamp, state.version))
            self._fired("stale_states: state %d stamped %s", state.header_id, state.timestamp)
        out = [state]
        if self._chance(plan.duplicate_states):
            out.append(state)
            self._fired("duplicate_states: state %d sent twice", state.header_id)
        held = self._held
        if isinstance(held, type(state)):
            self._fired("reorder_states: state %d sent after %d", held.header_id, state.header_id)
            out.append(held)
            self._held = None
        return out

    def _chance(self, rate: float) -> bool:
        return rate > 0.0 and (rate >= 1.0 or self._rng.random() < rate)
