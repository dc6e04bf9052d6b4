"""Structs of the ``state`` topic (mobile robot → fleet control), 3.0.0.

Renamed against 2.x (REFERENCE §6): ``mobileRobotPosition`` (``localized``), ``powerSupply``
(``stateOfCharge``, ``range``), ``activeEmergencyStop``, ``actionResult``, ``*Descriptor``;
new: ``instantActionStates`` (required), ``zoneActionStates``, ``zoneSets``, ``zoneRequests``,
``edgeRequests``, ``plannedPath``, ``intermediatePath`` and error translations.
:class:`MobileRobotPosition`, :class:`PlannedPath` and :class:`IntermediatePath` are shared
with ``visualization``.
"""

from __future__ import annotations

from vda5050.enums import InfoLevel, MapStatus
from vda5050.v2.base import HeaderId, VDAStruct
from vda5050.v2.state import ErrorReference, InfoReference, Load, Velocity
from vda5050.v3.enums import (
    ActionStatus,
    ActiveEmergencyStop,
    EdgeRequestType,
    ErrorLevel,
    OperatingMode,
    RequestStatus,
    ZoneRequestType,
    ZoneSetStatus,
)
from vda5050.v3.order import Trajectory

__all__ = [
    "ActionState",
    "EdgeRequest",
    "EdgeState",
    "Error",
    "ErrorReference",
    "InfoReference",
    "Information",
    "IntermediatePath",
    "Load",
    "MapState",
    "MobileRobotPosition",
    "NodeState",
    "NodeStatePosition",
    "PlannedPath",
    "PolylinePoint",
    "PowerSupply",
    "SafetyState",
    "State",
    "Translation",
    "Velocity",
    "ZoneRequest",
    "ZoneSetState",
]


class MapState(VDAStruct, kw_only=True):
    """An entry of ``state.maps``: a map version stored on the robot."""

    map_id: str
    map_version: str
    map_descriptor: str | None = None
    map_status: MapStatus


class ZoneSetState(VDAStruct, kw_only=True):
    """An entry of ``state.zoneSets``: a zone set stored on the robot."""

    zone_set_id: str
    map_id: str
    zone_set_status: ZoneSetStatus


class NodeStatePosition(VDAStruct, kw_only=True):
    """``nodeStates[].nodePosition``: 3.0 reports only the pose, no deviations."""

    x: float
    y: float
    theta: float | None = None
    map_id: str


class NodeState(VDAStruct, kw_only=True):
    """A released-or-horizon node still to be traversed (never the order's first node)."""

    node_id: str
    sequence_id: int
    node_descriptor: str | None = None
    released: bool
    node_position: NodeStatePosition | None = None


class EdgeState(VDAStruct, kw_only=True):
    """An edge of the current order still to be traversed."""

    edge_id: str
    sequence_id: int
    edge_descriptor: str | None = None
    released: bool
    trajectory: Trajectory | None = None


class PlannedPath(VDAStruct, kw_only=True):
    """The path a freely navigating robot plans to drive (3.0 §6.8)."""

    trajectory: Trajectory
    traversed_nodes: list[str] | None = None


class PolylinePoint(VDAStruct, kw_only=True):
    """A point of ``intermediatePath.polyline`` with its estimated time of arrival."""

    x: float
    y: float
    theta: float | None = None
    eta: str


class IntermediatePath(VDAStruct, kw_only=True):
    """Short-term path as a polyline with ETAs (3.0 §6.8)."""

    polyline: list[PolylinePoint]


class MobileRobotPosition(VDAStruct, kw_only=True):
    """Robot pose on a map (2.x ``agvPosition``; ``localized`` was ``positionInitialized``)."""

    x: float
    y: float
    theta: float
    map_id: str
    localized: bool
    localization_score: float | None = None
    deviation_range: float | None = None


class ZoneRequest(VDAStruct, kw_only=True):
    """A request for a RELEASE (ACCESS) or COORDINATED_REPLANNING zone (REPLANNING)."""

    request_id: str
    request_type: ZoneRequestType
    zone_id: str
    zone_set_id: str
    request_status: RequestStatus
    trajectory: Trajectory | None = None


class EdgeRequest(VDAStruct, kw_only=True):
    """A request for a corridor of a base edge with ``releaseRequired``."""

    request_id: str
    request_type: EdgeRequestType
    edge_id: str
    sequence_id: int
    request_status: RequestStatus


class ActionState(VDAStruct, kw_only=True):
    """Progress of one order, instant or zone action."""

    action_id: str
    action_type: str | None = None
    action_descriptor: str | None = None
    action_status: ActionStatus
    action_result: str | None = None


class PowerSupply(VDAStruct, kw_only=True):
    """Battery information (2.x ``batteryState``)."""

    state_of_charge: float
    battery_voltage: float | None = None
    battery_current: float | None = None
    battery_health: float | None = None
    charging: bool
    range: float | None = None


class Translation(VDAStruct, kw_only=True):
    """A translated text; ``translation_key`` is an ISO 639-1 language code."""

    translation_key: str
    translation_value: str


class Error(VDAStruct, kw_only=True):
    """An active error of the robot (levels: REFERENCE §3 G.36)."""

    error_type: str
    error_references: list[ErrorReference] | None = None
    error_description: str | None = None
    error_description_translations: list[Translation] | None = None
    error_hint: str | None = None
    error_hint_translations: list[Translation] | None = None
    error_level: ErrorLevel


class Information(VDAStruct, kw_only=True):
    """Informational message for visualisation/debugging only (never for logic)."""

    info_type: str
    info_references: list[InfoReference] | None = None
    info_descriptor: str | None = None
    info_level: InfoLevel


class SafetyState(VDAStruct, kw_only=True):
    """Emergency-stop and protective-field status."""

    active_emergency_stop: ActiveEmergencyStop
    field_violation: bool


class State(VDAStruct, kw_only=True):
    """``state`` message. ``loads`` absent means "unknown", ``[]`` means unloaded."""

    header_id: HeaderId
    timestamp: str
    version: str
    manufacturer: str
    serial_number: str
    maps: list[MapState] | None = None
    zone_sets: list[ZoneSetState] | None = None
    order_id: str
    order_update_id: int
    last_node_id: str
    last_node_sequence_id: int
    node_states: list[NodeState]
    edge_states: list[EdgeState]
    planned_path: PlannedPath | None = None
    intermediate_path: IntermediatePath | None = None
    mobile_robot_position: MobileRobotPosition | None = None
    velocity: Velocity | None = None
    loads: list[Load] | None = None
    driving: bool
    paused: bool | None = None
    new_base_request: bool | None = None
    zone_requests: list[ZoneRequest] | None = None
    edge_requests: list[EdgeRequest] | None = None
    distance_since_last_node: float | None = None
    action_states: list[ActionState]
    instant_action_states: list[ActionState]
    zone_action_states: list[ActionState] | None = None
    power_supply: PowerSupply
    operating_mode: OperatingMode
    errors: list[Error]
    information: list[Information] | None = None
    safety_state: SafetyState
