"""The live fleet model held in memory by `control`: one LiveVehicle per vehicle.

Plain Python, no ORM: handlers update it per message; the flusher turns it into rows and the
broadcaster into browser snapshots.
"""

import time
from dataclasses import dataclass, field
from datetime import datetime
from typing import Any

import msgspec

import vda5050
from control.execution import OrderExecution
from vda5050.enums import ConnectionState

VehicleKey = tuple[str, str]  # (manufacturer, serial number)


@dataclass
class LiveVehicle:
    """What `control` knows about one vehicle right now."""

    manufacturer: str
    serial_number: str
    interface_name: str
    version: str = "2.0.0"
    pk: int | None = None
    connection: str = "UNKNOWN"
    state: vda5050.State | None = None
    factsheet: dict[str, Any] | None = None
    factsheet_changed: bool = False
    visual_position: vda5050.AgvPosition | None = None
    last_seen: datetime | None = None
    last_state_monotonic: float = 0.0
    execution: OrderExecution | None = None
    decode_errors: int = 0
    needs_flush: bool = True
    needs_broadcast: bool = True
    was_available: bool = False

    @property
    def key(self) -> VehicleKey:
        return (self.manufacturer, self.serial_number)

    def mark_changed(self) -> None:
        self.needs_flush = True
        self.needs_broadcast = True

    def apply_state(self, state: vda5050.State, *, received_at: datetime) -> None:
        """Take a new state message as the vehicle's current state."""
        self.state = state
        self.version = state.version or self.version
        self.last_seen = received_at
        self.last_state_monotonic = time.monotonic()
        if state.agv_position is not None:
            self.visual_position = state.agv_position
        if self.connection in {"UNKNOWN", "OFFLINE", "CONNECTIONBROKEN"}:
            # A vehicle that sends state is connected, whatever a stale retained message said.
            self.connection = ConnectionState.ONLINE.value
        self.mark_changed()

    def apply_connection(self, message: vda5050.Connection, *, received_at: datetime) -> None:
        self.connection = str(message.connection_state)
        self.version = message.version or self.version
        self.last_seen = received_at
        self.mark_changed()

    def apply_factsheet(self, message: vda5050.Factsheet) -> None:
        self.factsheet = msgspec.to_builtins(message)
        self.factsheet_changed = True
        self.version = message.version or self.version
        self.needs_flush = True

    @property
    def is_available(self) -> bool:
        """Connected, in an automatic mode, localised on a node and without fatal errors."""
        state = self.state
        return (
            self.connection == ConnectionState.ONLINE.value
            and state is not None
            and str(state.operating_mode) in {"AUTOMATIC", "SEMIAUTOMATIC"}
            and not state.paused
            and bool(state.last_node_id)
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
        if pk is not None:
            self._by_pk[pk] = vehicle
