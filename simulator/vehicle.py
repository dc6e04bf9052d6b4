"""Pure state machine of one virtual AGV: orders, driving, actions, battery, operating mode
and scripted misbehaviour (:mod:`simulator.saboteur`). No MQTT here.

Time only advances through :meth:`VirtualVehicle.tick`, so tests drive it with a fake
clock. Every call that changes what the state message would report raises the "state due"
flag (REFERENCE §3 F.30); the transport pops it with :meth:`VirtualVehicle.take_state_due`.
"""

from __future__ import annotations

import logging
import math

from simulator import intake, messages, wire
from simulator.config import StartPose, VehicleConfig, normalize_angle
from simulator.delays import DelayInjector
from simulator.execution import ActionExecutor
from simulator.maps import MapStore, ZoneRequests
from simulator.misbehaviour import Misbehaviour
from simulator.orders import Point, Step
from simulator.saboteur import Saboteur
from vda5050 import (
    Connection,
    Error,
    ErrorReference,
    Factsheet,
    InstantActions,
    Load,
    Order,
    State,
    Visualization,
)
from vda5050.enums import ConnectionState, ErrorLevel, ErrorType, OperatingMode
from vda5050.headers import HeaderCounter

__all__ = ["StartPose", "VehicleConfig", "VirtualVehicle", "normalize_angle"]

log = logging.getLogger(__name__)

_EPS = 1e-6
# Rejection errors are kept until the next accepted order; cap them so a master that
# keeps resending a bad order cannot grow the state message without bound.
_MAX_ORDER_ERRORS = 10


class VirtualVehicle:
    """One simulated AGV. Not thread-safe: the fleet serialises calls with a lock."""

    def __init__(
        self,
        config: VehicleConfig,
        start: StartPose,
        *,
        known_nodes: dict[str, Point] | None = None,
    ) -> None:
        self.config = config
        self.map_store = MapStore.booted(start.map_id, config.map_version)  # 2.1+: state.maps
        self.zone_requests = ZoneRequests()  # 3.0: access requests for RELEASE zones
        self.known_nodes = dict(known_nodes or {})
        self.headers = HeaderCounter()
        self.map_id = start.map_id
        self.x, self.y, self.theta = start.x, start.y, normalize_angle(start.theta)
        self.position_initialized = True
        self.order_id = ""
        self.order_update_id = 0
        self.last_order: Order | None = None  # latest accepted order message (3.0 resends)
        self.last_node_id = start.node_id
        self.last_node_sequence_id = 0
        self.pending: list[Step] = []
        self.driving = False
        self.paused = False
        self.speed_now = 0.0
        self.distance_since_last_node = 0.0
        self.battery = max(0.0, min(100.0, config.battery_start))
        self.charging = False
        self.loads: list[Load] = []
        self.order_errors: list[Error] = []
        self.injected_errors: list[Error] = []
        self.action_errors: list[Error] = []  # failed actions, until the next new order
        self.fatal_stop: Error | None = None  # halts driving while it is in injected_errors
        self.cancelled = False
        self.operating_mode = OperatingMode.AUTOMATIC
        self.sim_time = 0.0
        self.actions = ActionExecutor(self)
        self._state_due = True
        self.factsheet_due = True
        self.saboteur = Saboteur(self, config.misbehaviour)
        self.delays: DelayInjector | None = None  # delay injection (simulator.delays)

    # ------------------------------------------------------------------ events
    def mark_state_due(self) -> None:
        """Something reportable changed: publish a state message soon."""
        self._state_due = True

    def take_state_due(self) -> bool:
        """Return and clear the "state due" flag."""
        due, self._state_due = self._state_due, False
        return due

    def take_factsheet_due(self) -> bool:
        """Return and clear the "factsheet requested" flag."""
        due, self.factsheet_due = self.factsheet_due, False
        return due

    # ------------------------------------------------------------------ queries
    @property
    def maps(self) -> frozenset[str]:
        """Ids of the maps the vehicle holds (any version)."""
        return self.map_store.map_ids()

    @property
    def has_order(self) -> bool:
        """True while nodes/edges are pending or order actions are not terminal."""
        return bool(self.pending) or self.actions.order_busy

    @property
    def idle(self) -> bool:
        """REFERENCE §3 C.16: no node/edge states and every action terminal."""
        return not self.pending and self.actions.all_terminal

    @property
    def position(self) -> Point:
        """Current (x, y) in metres."""
        return (self.x, self.y)

    # ------------------------------------------------------------------ orders
    def on_order(self, order: Order) -> bool:
        """Accept or reject an order/update; returns True if it was accepted now (a
        dropped, delayed or identically resent order returns False without an error)."""
        return intake.receive(self, order)

    def reject_undecodable(self, reason: str) -> None:
        """An order payload that does not even decode is a validationError too."""
        self.add_order_error(self.error_type(ErrorType.VALIDATION_ERROR), reason, [])
        self.mark_state_due()

    def error_type(self, error_type: str, v3_type: str | None = None) -> str:
        """The errorType to report: ``error_type`` (2.x) or, for a 3.0 vehicle, ``v3_type``
        or the 3.0 name of ``error_type`` (REFERENCE §3 C.18)."""
        if self.config.major < 3:
            return error_type
        return v3_type or wire.V3_ERROR_TYPES.get(error_type, error_type)

    def add_order_error(self, error_type: str, text: str, refs: list[ErrorReference]) -> None:
        """Report a WARNING order error until the next accepted order (capped list)."""
        error = Error(
            error_type=error_type,
            error_references=refs or None,
            error_description=text,
            error_level=ErrorLevel.WARNING,
        )
        self.order_errors = [*self.order_errors, error][-_MAX_ORDER_ERRORS:]

    # ------------------------------------------------------------------ instant actions
    def on_instant_actions(self, message: InstantActions) -> None:
        """Execute instant actions in list order."""
        for action in message.actions:
            self.actions.run_instant(action)
        self.mark_state_due()

    def add_no_order_to_cancel(self, action_id: str) -> None:
        """cancelOrder without an active order (REFERENCE §3 D.20)."""
        self.add_order_error(
            self.error_type(ErrorType.NO_ORDER_TO_CANCEL),
            "cancelOrder received but there is no order to cancel",
            [ErrorReference(reference_key="actionId", reference_value=action_id)],
        )

    def add_invalid_instant_action(self, action_id: str, reason: str) -> None:
        """3.0: an instant action that cannot be executed is INVALID_INSTANT_ACTION."""
        refs = [ErrorReference(reference_key="actionId", reference_value=action_id)]
        self.add_order_error("INVALID_INSTANT_ACTION", reason, refs)

    def cancel_order(self) -> None:
        """Drop everything after the node we are heading to (or all, if on a node)."""
        self.cancelled = True
        moving_on_edge = self.distance_since_last_node > _EPS or (
            bool(self.pending) and self.pending[0].edge is None
        )
        if self.pending and self.pending[0].released and moving_on_edge:
            self.pending = self.pending[:1]
        else:
            self.pending = []
        self.mark_state_due()

    def init_position(self, x: float, y: float, theta: float, map_id: str, node_id: str) -> None:
        """Relocate the vehicle (initPosition)."""
        self.x, self.y, self.theta = x, y, normalize_angle(theta)
        self.map_id = map_id
        self.last_node_id = node_id
        self.last_node_sequence_id = 0
        self.distance_since_last_node = 0.0
        self.position_initialized = True
        self.mark_state_due()

    # ------------------------------------------------------------------ faults
    def inject_error(
        self, error_type: str, level: ErrorLevel = ErrorLevel.WARNING, description: str = ""
    ) -> None:
        """Report an artificial error until :meth:`clear_injected_errors` (fault injection)."""
        self.injected_errors.append(
            Error(error_type=error_type, error_description=description or None, error_level=level)
        )
        self.mark_state_due()

    def clear_injected_errors(self, error_type: str | None = None) -> None:
        """Remove injected and action errors (all, or those of one type)."""

        def keep(errors: list[Error]) -> list[Error]:
            return [e for e in errors if error_type is not None and e.error_type != error_type]

        self.injected_errors = keep(self.injected_errors)
        self.action_errors = keep(self.action_errors)
        if self.fatal_stop is not None and self.fatal_stop not in self.injected_errors:
            self.fatal_stop = None
        self.mark_state_due()

    def misbehave(self, plan: Misbehaviour) -> None:
        """Replace the scripted misbehaviour (``Misbehaviour()`` = behave again)."""
        previous = self.saboteur
        self.saboteur = Saboteur(self, plan)
        self.saboteur.adopt(previous)
        self.mark_state_due()

    def report_action_failure(self, action_id: str, action_type: str) -> None:
        """A scripted action failure: WARNING ``actionFailed`` until the next new order."""
        refs = [
            ErrorReference(reference_key="actionId", reference_value=action_id),
            ErrorReference(reference_key="actionType", reference_value=action_type),
        ]
        self.action_errors = [
            *self.action_errors,
            Error(
                error_type="actionFailed",
                error_references=refs,
                error_description=f"{action_type} failed (simulated misbehaviour)",
                error_level=ErrorLevel.WARNING,
            ),
        ][-_MAX_ORDER_ERRORS:]

    def set_operating_mode(self, mode: OperatingMode) -> None:
        """Switch mode; entering or leaving MANUAL/SERVICE/TEACHIN clears the order (2.x,
        REFERENCE §3 I.40): the vehicle stops, order actions fail, node/edge states empty,
        ids stay, and the next order needs a new orderId."""
        mode = OperatingMode(mode)
        if mode == self.operating_mode:
            return
        previous, self.operating_mode = self.operating_mode, mode
        log.info("%s: operating mode %s -> %s", self.config.serial_number, previous, mode)
        if (previous not in intake.ORDER_MODES or mode not in intake.ORDER_MODES) and (
            self.has_order
        ):
            self.actions.abort_order(f"order cleared: operating mode {mode}")
            self.pending = []
            self.cancelled = True
            self.driving, self.speed_now = False, 0.0
        self.mark_state_due()

    # ------------------------------------------------------------------ simulation
    def tick(self, dt: float) -> None:
        """Advance the simulation by ``dt`` wall seconds (scaled by the time-lapse factor)."""
        sim_dt = max(0.0, dt) * self.config.time_scale
        self.sim_time += sim_dt
        was_driving = self.driving
        self.saboteur.advance()
        for order in self.saboteur.due_orders():
            intake.process(self, order)
        if not self.paused:
            self.actions.advance(sim_dt)
        moved = self._drive(sim_dt)
        if self.saboteur.fatal_due():
            self._stop_fatally()
        self._update_battery(sim_dt, moved)
        self.actions.check_cancel_done()
        if self.driving != was_driving:
            self.mark_state_due()

    def _can_drive(self) -> bool:
        return (
            bool(self.pending)
            and self.pending[0].released
            and not self.paused
            and not self.actions.blocks_driving
            and self.battery > 0.0
            and self.fatal_stop is None
            and self._zones_allow()
        )

    def _zones_allow(self) -> bool:
        """3.0: a RELEASE zone ahead needs fleet control's grant first (simulator.maps)."""
        if self.config.major < 3:
            return True
        allowed, changed = self.zone_requests.may_drive(
            self.map_store, self.position, self.pending[0].target
        )
        if changed:
            self.mark_state_due()
        return allowed

    def _stop_fatally(self) -> None:
        error = Error(
            error_type=self.saboteur.plan.fatal_error,
            error_description="simulated FATAL error while driving; clear it to go on",
            error_level=ErrorLevel.FATAL,
        )
        self.injected_errors.append(error)
        self.fatal_stop = error
        self.driving, self.speed_now = False, 0.0
        self.mark_state_due()

    def _drive(self, sim_dt: float) -> float:
        """Move towards the next node; returns metres driven."""
        if not self._can_drive() or (
            self.delays is not None
            and self.pending[0].edge is not None  # a move along an edge, not the start node
            and self.delays.holds((self.order_id, self.pending[0].key), self.sim_time)
        ):
            self.driving, self.speed_now = False, 0.0
            return 0.0
        if self.charging:
            # Driving off the charger disconnects it, like a real charging contact would.
            self.charging = False
            self.mark_state_due()
        step = self.pending[0]
        speed = self.config.speed
        if step.edge is not None and step.edge.max_speed:
            speed = min(speed, step.edge.max_speed)
        dx, dy = step.target[0] - self.x, step.target[1] - self.y
        remaining = math.hypot(dx, dy)
        travel = min(remaining, speed * sim_dt)
        if remaining > _EPS:
            self.theta = math.atan2(dy, dx)
            self.x += dx / remaining * travel
            self.y += dy / remaining * travel
            self.distance_since_last_node += travel
        self.driving, self.speed_now = True, speed
        if remaining - travel <= _EPS:
            self._arrive(step)
            # Keep "driving" across a node we pass through so the flag does not flap.
            self.driving = self._can_drive()
            self.speed_now = speed if self.driving else 0.0
        return travel

    def _arrive(self, step: Step) -> None:
        self.pending.pop(0)
        self.x, self.y = float(step.target[0]), float(step.target[1])
        pos = step.node.node_position
        if pos is not None and pos.theta is not None:
            self.theta = normalize_angle(pos.theta)
        self.last_node_id, self.last_node_sequence_id = step.key
        self.distance_since_last_node = 0.0
        self.actions.trigger_node(step.key)
        self.saboteur.node_passed()
        self.mark_state_due()

    def _update_battery(self, sim_dt: float, metres: float) -> None:
        cfg = self.config
        before = self.battery
        if self.charging:
            self.battery += cfg.battery_charge_per_second * sim_dt
        else:
            self.battery -= cfg.battery_idle_drain_per_second * sim_dt
        self.battery -= cfg.battery_drain_per_metre * metres
        self.battery = max(0.0, min(100.0, self.battery))
        if self.charging and self.battery >= 100.0 > before:
            self.mark_state_due()

    # ------------------------------------------------------------------ messages
    def build_state(self) -> State:
        """Assemble a state message; consumes one state headerId."""
        return messages.state_message(self)

    def build_states(self) -> list[State]:
        """The state messages to publish now: one, or what the misbehaviour makes of it
        (none while held back, two when duplicated or when a held one follows)."""
        return self.saboteur.shape_states(messages.state_message(self))

    @property
    def silent(self) -> bool:
        """True while a scripted silence lasts (no state, no visualization)."""
        return self.saboteur.silent

    def build_visualization(self) -> Visualization:
        """Assemble a visualization message; consumes one visualization headerId."""
        return messages.visualization_message(self)

    def build_connection(self, state: ConnectionState) -> Connection:
        """Assemble a connection message; consumes one connection headerId."""
        return messages.connection_message(self, state)

    def build_factsheet(self) -> Factsheet:
        """Assemble the factsheet; consumes one factsheet headerId."""
        return messages.factsheet_message(self)
