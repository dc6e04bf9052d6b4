"""The live fleet model held in memory by `control`: one LiveVehicle per vehicle.

Plain Python, no ORM: handlers update it per message; the flusher turns it into rows and the
broadcaster into browser snapshots.
"""

import time
from dataclasses import dataclass, field, replace
from datetime import UTC, datetime
from typing import TYPE_CHECKING, Any

import msgspec

import vda5050
from control.capabilities import ORDER_MODES, Capabilities
from control.execution import OrderExecution
from control.session import Link, ProtocolSession

if TYPE_CHECKING:
    from control.snapshots import RowParts

TRACKED_INSTANT_ACTIONS = 20  # the latest instant actions kept per vehicle for display
# The live page is sent a vehicle's clock skew again once it moved by this much (seconds):
# a skew is display only, and its jitter alone made every idle vehicle's row change.
SHOWN_SKEW_STEP = 0.1


@dataclass
class InstantActionTrack:
    """An instant action we sent (or refused), followed to its end in the vehicle's state."""

    action_id: str
    action_type: str
    status: str  # SENT, REFUSED, then the vehicle's actionStatus
    reason: str = ""
    request: str | None = None  # the caller's reference, if any


VehicleKey = tuple[str, str]  # (manufacturer, serial number)


@dataclass
class LiveVehicle:
    """What `control` knows about one vehicle right now."""

    manufacturer: str
    serial_number: str
    interface_name: str
    version: str = "2.0.0"
    pk: int | None = None
    dialect: str = "STANDARD"  # robots.Vehicle.Dialect: deviations to honour when sending
    session: ProtocolSession = field(default_factory=ProtocolSession)
    state: vda5050.State | None = None
    factsheet: dict[str, Any] | None = None
    factsheet_changed: bool = False
    factsheet_requested: bool = False
    capabilities: Capabilities | None = None
    instant_actions: dict[str, InstantActionTrack] = field(default_factory=dict)
    # Outcomes of operators' commands (tracks with a request id) for the flusher to record.
    command_outcomes: list[InstantActionTrack] = field(default_factory=list)
    visual_position: vda5050.AgvPosition | None = None
    last_seen: datetime | None = None
    execution: OrderExecution | None = None
    last_order_sent: float = float("-inf")  # monotonic; for the factsheet's minOrderInterval
    # 3.0 action-state bookkeeping (control.action_states): the instant actions we sent (to
    # tell them from order actions in the merged actionStates), RETRIABLE actions a retry or
    # skipRetry was sent for, and when clearInstantActions last went out (monotonic).
    sent_instant: dict[str, None] = field(default_factory=dict)
    answered_retriable: dict[str, float] = field(default_factory=dict)  # id -> monotonic
    cleared_at: float = float("-inf")
    needs_flush: bool = True
    # What its last snapshot row said besides motion (snapshots.material), and when it was
    # written (monotonic): a change of motion alone waits for the motion flush interval.
    flushed_material: tuple[Any, ...] | None = field(default=None, repr=False, compare=False)
    flushed_at: float = float("-inf")
    needs_broadcast: bool = True
    was_available: bool = False
    last_link: Link = Link.UNKNOWN
    # The parts of its last live-page row, reused while their inputs stay (snapshots.live_row).
    row_parts: "RowParts | None" = field(default=None, repr=False, compare=False)

    @property
    def key(self) -> VehicleKey:
        return (self.manufacturer, self.serial_number)

    @property
    def connection(self) -> str:
        """The connection as dispatch should see it now (ONLINE only with recent states)."""
        return self.session.link(time.monotonic()).value

    def mark_changed(self) -> None:
        self.needs_flush = True
        self.needs_broadcast = True

    def apply_state(self, state: vda5050.State, *, received_at: datetime) -> bool:
        """Take a new state message; True if the vehicle was unknown or silent before."""
        woke_up = self.session.on_state(time.monotonic(), _skew(state.timestamp, received_at))
        before, self.state = self.state, state
        self.version = state.version or self.version
        self.last_seen = received_at
        position = state.agv_position
        if position is not None:
            self.visual_position = position
        if self.instant_actions:  # nothing to follow before control sent one
            self.follow_instant_actions(state)
        self.needs_flush = True
        if not self.needs_broadcast:
            # An idle vehicle repeats the same state twice a second: its live row is built
            # again only when something the page shows changed (a vehicle with an order
            # always: whom it waits for and its reservations change without its state).
            self.needs_broadcast = (
                woke_up
                or before is None
                or self.execution is not None
                or shows_change(before, state)
                or self._skew_moved()
            )
        return woke_up

    def apply_pose(self, position: vda5050.AgvPosition) -> None:
        """Take a visualization message's pose (the live page is told only if it moved)."""
        if position != self.visual_position:
            self.needs_broadcast = True
        self.visual_position = position

    def _skew_moved(self) -> bool:
        """Whether the clock skew moved by `SHOWN_SKEW_STEP` since the live page got it."""
        skew, parts = self.session.clock_skew, self.row_parts
        shown = parts.row["clock_skew"] if parts is not None and parts.row is not None else None
        if skew is None or shown is None:
            return skew is not shown
        return bool(abs(skew - shown) >= SHOWN_SKEW_STEP)

    def apply_connection(self, message: vda5050.Connection, *, received_at: datetime) -> bool:
        """Take a connection message; True if the vehicle (re)connected."""
        reconnected = self.session.on_connection(
            str(message.connection_state),
            time.monotonic(),
            identity=(message.header_id, message.timestamp),
        )
        self.version = message.version or self.version
        self.last_seen = received_at
        self.mark_changed()
        return reconnected

    def keep_battery_charging(self, raw: Any) -> None:
        """Keep a 3.0 factsheet's `batteryCharging` (no 2.x field holds it) in the stored
        factsheet under `vehicleConfig`: dispatch gives a vehicle below its
        `criticalLowChargingLevel` no transport orders (REFERENCE J.46)."""
        config = getattr(raw, "mobile_robot_configuration", None)
        charging = getattr(config, "battery_charging", None)
        if self.factsheet is None or charging is None:
            return
        vehicle_config = dict(self.factsheet.get("vehicleConfig") or {})
        vehicle_config["batteryCharging"] = msgspec.to_builtins(charging)
        self.factsheet["vehicleConfig"] = vehicle_config

    def apply_factsheet(self, message: vda5050.Factsheet) -> None:
        self.factsheet = msgspec.to_builtins(message)
        self.capabilities = Capabilities.from_factsheet(message)
        self.factsheet_changed = True
        self.version = message.version or self.version
        interval = message.protocol_limits.timing.default_state_interval
        if interval:
            self.session.state_interval = interval
        self.needs_flush = True

    def track(self, action: InstantActionTrack) -> None:
        self.instant_actions[action.action_id] = action
        self._report(action)
        while len(self.instant_actions) > TRACKED_INSTANT_ACTIONS:
            del self.instant_actions[next(iter(self.instant_actions))]
        self.needs_broadcast = True

    def follow_instant_actions(self, state: vda5050.State) -> None:
        """Update the tracked instant actions from the state's actionStates (2.x lists them)."""
        tracked_by_id = self.instant_actions
        for action_state in state.action_states:
            tracked = tracked_by_id.get(action_state.action_id)
            if tracked is not None and tracked.status != str(action_state.action_status):
                tracked.status = str(action_state.action_status)
                tracked.reason = action_state.result_description or ""
                self._report(tracked)
                self.needs_broadcast = True  # the page lists the latest instant actions

    def _report(self, action: InstantActionTrack) -> None:
        if action.request is not None:
            self.command_outcomes.append(replace(action))  # a copy: later changes come anew
            self.needs_flush = True

    @property
    def is_available(self) -> bool:
        """Connected, in a mode that takes orders, localised on a node, without fatal errors."""
        state = self.state
        return (
            self.connection == Link.ONLINE
            and state is not None
            and str(state.operating_mode) in ORDER_MODES  # incl. 3.0 INTERVENED (I.41)
            and not state.paused
            and bool(state.last_node_id)
            # F.33: an unlocalised vehicle cannot be routed (no position = line-guided, fine)
            and (state.agv_position is None or state.agv_position.position_initialized)
            # F.34: a vehicle reports charging false only once it can take orders again (after
            # stopCharging); until then a new order waits (3.0 powerSupply.charging, adapted)
            and not state.battery_state.charging
            and not any(str(e.error_level) == "FATAL" for e in state.errors)
        )

    @property
    def is_idle(self) -> bool:
        """No order being driven and no action running: a new order may be sent (REFERENCE C.16)."""
        state = self.state
        if state is None or state.node_states or state.edge_states:
            return False
        return all(str(a.action_status) in {"FINISHED", "FAILED"} for a in state.action_states)


@dataclass
class Fleet:
    """All live vehicles, by identity."""

    vehicles: dict[VehicleKey, LiveVehicle] = field(default_factory=dict)
    _by_pk: dict[int, LiveVehicle] = field(default_factory=dict)

    def get_or_add(self, manufacturer: str, serial_number: str, interface_name: str) -> LiveVehicle:
        key = (manufacturer, serial_number)
        vehicle = self.vehicles.get(key)
        if vehicle is None:
            vehicle = LiveVehicle(manufacturer, serial_number, interface_name)
            self.vehicles[key] = vehicle
        return vehicle

    def by_pk(self, pk: int) -> LiveVehicle | None:
        return self._by_pk.get(pk)

    def set_pk(self, vehicle: LiveVehicle, pk: int | None) -> None:
        """Record the registry id of `vehicle` (known after the flusher registered it)."""
        vehicle.pk = pk
        vehicle.needs_broadcast = True  # the page's rows carry it as their id
        if pk is not None:
            self._by_pk[pk] = vehicle


def shows_change(before: vda5050.State, after: vda5050.State) -> bool:
    """Whether state `after` changes what the live page shows of a vehicle whose last state
    was `before`: any field but the header id, the timestamp and the battery's readings
    (the page shows the charge to 0.1 %, and whether it charges). One copy and one
    comparison, both in C (msgspec)."""
    battery, earlier = after.battery_state, before.battery_state
    if battery.charging != earlier.charging or round(battery.battery_charge, 1) != round(
        earlier.battery_charge, 1
    ):
        return True
    rest = msgspec.structs.replace(
        after, header_id=before.header_id, timestamp=before.timestamp, battery_state=earlier
    )
    return bool(rest != before)


def _skew(timestamp: str, received_at: datetime) -> float | None:
    """Seconds our clock is ahead of the vehicle's (display only, never used for ordering)."""
    try:  # fast path, once per state message: Python 3.11 reads the usual forms (Z, offsets)
        sent = datetime.fromisoformat(timestamp)
    except (TypeError, ValueError):
        try:  # the tolerant parser for the rest (lowercase z, odd spacing)
            sent = vda5050.parse_timestamp(timestamp)
        except vda5050.TimestampError:
            return None
    if sent.tzinfo is None:
        sent = sent.replace(tzinfo=UTC)  # the protocol's timestamps are UTC
    return (received_at - sent).total_seconds()
