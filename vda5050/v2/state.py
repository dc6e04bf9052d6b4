"""Structs of the ``state`` topic (AGV → master control), 2.0.0 and 2.1.0.

:class:`AgvPosition` and :class:`Velocity` are also used by ``visualization``.
"""

from __future__ import annotations

from vda5050.enums import (
    ActionStatus,
    ErrorLevel,
    EStop,
    InfoLevel,
    MapStatus,
    OperatingMode,
)
from vda5050.v2.base import BoundingBoxReference, HeaderId, LoadDimensions, VDAStruct
from vda5050.v2.order import NodePosition, Trajectory


class MapState(VDAStruct, kw_only=True):
    """An entry of ``state.maps`` (2.1): a map version stored on the vehicle."""

    map_id: str
    map_version: str
    map_description: str | None = None
    map_status: MapStatus


class NodeState(VDAStruct, kw_only=True):
    """A node of the current order still to be traversed."""

    node_id: str
    sequence_id: int
    node_description: str | None = None
    released: bool
    node_position: NodePosition | None = None


class EdgeState(VDAStruct, kw_only=True):
    """An edge of the current order still to be traversed."""

    edge_id: str
    sequence_id: int
    edge_description: str | None = None
    released: bool
    trajectory: Trajectory | None = None


class AgvPosition(VDAStruct, kw_only=True):
    """Vehicle pose on a map (state and visualization)."""

    x: float
    y: float
    theta: float
    map_id: str
    map_description: str | None = None
    position_initialized: bool
    localization_score: float | None = None
    deviation_range: float | None = None


class Velocity(VDAStruct, kw_only=True):
    """Vehicle velocity in vehicle coordinates (state and visualization)."""

    vx: float | None = None
    vy: float | None = None
    omega: float | None = None


class Load(VDAStruct, kw_only=True):
    """A load carried by the vehicle. All fields are optional on the wire."""

    load_id: str | None = None
    load_type: str | None = None
    load_position: str | None = None
    bounding_box_reference: BoundingBoxReference | None = None
    load_dimensions: LoadDimensions | None = None
    weight: float | None = None


class ActionState(VDAStruct, kw_only=True):
    """Progress of one order or instant action."""

    action_id: str
    action_type: str | None = None
    action_description: str | None = None
    action_status: ActionStatus
    result_description: str | None = None


class BatteryState(VDAStruct, kw_only=True):
    """Battery information.

    ``battery_health`` is an integer in the 2.0 schema and a number in 2.1; send whole
    numbers to 2.0 vehicles.
    """

    battery_charge: float
    battery_voltage: float | None = None
    battery_health: float | None = None
    charging: bool
    reach: float | None = None


class ErrorReference(VDAStruct, kw_only=True):
    """Reference (e.g. ``orderId``/``actionId``) attached to an error."""

    reference_key: str
    reference_value: str


class Error(VDAStruct, kw_only=True):
    """An active error of the vehicle. ``error_hint`` is 2.1 only."""

    error_type: str
    error_references: list[ErrorReference] | None = None
    error_description: str | None = None
    error_hint: str | None = None
    error_level: ErrorLevel


class InfoReference(VDAStruct, kw_only=True):
    """Reference attached to an information entry."""

    reference_key: str
    reference_value: str


class Information(VDAStruct, kw_only=True):
    """Informational message for visualisation/debugging only (never for logic)."""

    info_type: str
    info_references: list[InfoReference] | None = None
    info_description: str | None = None
    info_level: InfoLevel


class SafetyState(VDAStruct, kw_only=True):
    """Emergency-stop and protective-field status."""

    e_stop: EStop
    field_violation: bool


class State(VDAStruct, kw_only=True):
    """``state`` message. ``maps`` is 2.1 only; ``loads`` absent means "unknown"."""

    header_id: HeaderId
    timestamp: str
    version: str
    manufacturer: str
    serial_number: str
    maps: list[MapState] | None = None
    order_id: str
    order_update_id: int
    zone_set_id: str | None = None
    last_node_id: str
    last_node_sequence_id: int
    driving: bool
    paused: bool | None = None
    new_base_request: bool | None = None
    distance_since_last_node: float | None = None
    operating_mode: OperatingMode
    node_states: list[NodeState]
    edge_states: list[EdgeState]
    agv_position: AgvPosition | None = None
    velocity: Velocity | None = None
    loads: list[Load] | None = None
    action_states: list[ActionState]
    battery_state: BatteryState
    errors: list[Error]
    information: list[Information] | None = None
    safety_state: SafetyState
