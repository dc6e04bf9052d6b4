"""Structs of the ``factsheet`` topic (robot → fleet control, retained), 3.0.0.

Renamed against 2.x (REFERENCE §6): ``agv*`` → ``mobileRobot*``, ``max*``/``min*`` →
``maximum*``/``minimum*``, ``maxStringLens`` → ``maximumStringLengths``, ``maxArrayLens`` →
``maximumArrayLengths``, envelopes ``set`` → ``envelope2dId``/``envelope3dId`` and
``polygonPoints`` → ``vertices``, ``vehicleConfig`` → ``mobileRobotConfiguration``. Follows
the 3.0.0-main schema (boolean ``pauseAllowed``/``cancelAllowed``, ``mobileRobotKinematics``).
"""

from __future__ import annotations

from typing import Any

import msgspec

from vda5050.enums import Support
from vda5050.v2.base import BoundingBoxReference, HeaderId, LoadDimensions, VDAStruct
from vda5050.v2.factsheet import NetworkConfig, OptionalParameter, VersionInfo, WheelPosition
from vda5050.v3.enums import ActionScope, BlockingType, ValueDataType, ZoneType
from vda5050.v3.zones import Vertex

__all__ = [
    "ActionParameterSpec",
    "BatteryCharging",
    "Envelope2d",
    "Envelope3d",
    "Factsheet",
    "LoadSet",
    "LoadSpecification",
    "MaximumArrayLengths",
    "MaximumStringLengths",
    "MobileRobotAction",
    "MobileRobotConfiguration",
    "MobileRobotGeometry",
    "NetworkConfig",
    "OptionalParameter",
    "PhysicalParameters",
    "ProtocolFeatures",
    "ProtocolLimits",
    "Support",
    "Timing",
    "TypeSpecification",
    "VersionInfo",
    "WheelDefinition",
    "WheelPosition",
]


class TypeSpecification(VDAStruct, kw_only=True):
    """Robot class, kinematics and capabilities; the string fields are extensible enums."""

    series_name: str
    series_description: str | None = None
    mobile_robot_kinematics: str
    mobile_robot_class: str
    maximum_load_mass: float
    localization_types: list[str]
    navigation_types: list[str]
    supported_zones: list[ZoneType] | None = None


class PhysicalParameters(VDAStruct, kw_only=True):
    """Speeds (m/s, rad/s), accelerations (m/s²) and dimensions (m)."""

    minimum_speed: float
    maximum_speed: float
    minimum_angular_speed: float | None = None
    maximum_angular_speed: float | None = None
    maximum_acceleration: float
    maximum_deceleration: float
    minimum_height: float
    maximum_height: float
    width: float
    length: float


class MaximumStringLengths(VDAStruct, kw_only=True):
    """Maximum string lengths the robot accepts (absent = no limit)."""

    maximum_message_length: int | None = None
    maximum_topic_serial_length: int | None = None
    maximum_topic_element_length: int | None = None
    maximum_id_length: int | None = None
    id_numerical_only: bool | None = None
    maximum_load_id_length: int | None = None


def _key(name: str) -> Any:
    return msgspec.field(default=None, name=name)


class MaximumArrayLengths(VDAStruct, kw_only=True):
    """Maximum array lengths the robot accepts (absent = no limit); dotted wire names."""

    order_nodes: int | None = _key("order.nodes")
    order_edges: int | None = _key("order.edges")
    node_actions: int | None = _key("node.actions")
    edge_actions: int | None = _key("edge.actions")
    actions_actions_parameters: int | None = _key("actions.actionsParameters")
    instant_actions: int | None = _key("instantActions")
    trajectory_knot_vector: int | None = _key("trajectory.knotVector")
    trajectory_control_points: int | None = _key("trajectory.controlPoints")
    zone_set_zones: int | None = _key("zoneSet.zones")
    state_node_states: int | None = _key("state.nodeStates")
    state_edge_states: int | None = _key("state.edgeStates")
    state_loads: int | None = _key("state.loads")
    state_action_states: int | None = _key("state.actionStates")
    state_instant_action_states: int | None = _key("state.instantActionStates")
    state_zone_action_states: int | None = _key("state.zoneActionStates")
    state_errors: int | None = _key("state.errors")
    state_information: int | None = _key("state.information")
    error_error_references: int | None = _key("error.errorReferences")
    information_info_references: int | None = _key("information.infoReferences")


class Timing(VDAStruct, kw_only=True):
    """Timing limits in seconds."""

    minimum_order_interval: float
    minimum_state_interval: float
    default_state_interval: float | None = None
    visualization_interval: float | None = None


class ProtocolLimits(VDAStruct, kw_only=True):
    """Protocol limits; fleet control must size and throttle messages accordingly."""

    maximum_string_lengths: MaximumStringLengths
    maximum_array_lengths: MaximumArrayLengths
    timing: Timing


class ActionParameterSpec(VDAStruct, kw_only=True):
    """Declaration of one parameter of an action the robot supports."""

    key: str
    value_data_type: ValueDataType
    description: str | None = None
    is_optional: bool | None = None


class MobileRobotAction(VDAStruct, kw_only=True):
    """An action type the robot supports (2.x ``agvActions``)."""

    action_type: str
    action_description: str | None = None
    action_scopes: list[ActionScope]
    action_parameters: list[ActionParameterSpec] | None = None
    action_result: str | None = None
    blocking_types: list[BlockingType] | None = None
    pause_allowed: bool
    cancel_allowed: bool


class ProtocolFeatures(VDAStruct, kw_only=True):
    """Supported optional parameters and actions."""

    optional_parameters: list[OptionalParameter]
    mobile_robot_actions: list[MobileRobotAction]


class WheelDefinition(VDAStruct, kw_only=True):
    """One wheel of the robot; ``type`` is an extensible enum (DRIVE, CASTER, ...)."""

    type: str
    is_active_driven: bool
    is_active_steered: bool
    position: WheelPosition
    diameter: float
    width: float
    center_displacement: float | None = None
    constraints: str | None = None


class Envelope2d(VDAStruct, kw_only=True):
    """2D envelope (footprint) polygon."""

    envelope2d_id: str = msgspec.field(name="envelope2dId")
    vertices: list[Vertex]
    description: str | None = None


class Envelope3d(VDAStruct, kw_only=True):
    """3D envelope, inline (``data``) or by ``url``."""

    envelope3d_id: str = msgspec.field(name="envelope3dId")
    format: str
    data: dict[str, Any] | None = None
    url: str | None = None
    description: str | None = None


class MobileRobotGeometry(VDAStruct, kw_only=True):
    """Wheels and envelopes of the robot."""

    wheel_definitions: list[WheelDefinition] | None = None
    envelopes2d: list[Envelope2d] | None = None
    envelopes3d: list[Envelope3d] | None = None


class LoadSet(VDAStruct, kw_only=True):
    """A load handling set (LIF ``loadSetNames`` refer to ``set_name``)."""

    set_name: str
    load_type: str
    load_positions: list[str] | None = None
    bounding_box_reference: BoundingBoxReference | None = None
    load_dimensions: LoadDimensions | None = None
    maximum_weight: float | None = None
    minimum_loadhandling_height: float | None = None
    maximum_loadhandling_height: float | None = None
    minimum_loadhandling_depth: float | None = None
    maximum_loadhandling_depth: float | None = None
    minimum_loadhandling_tilt: float | None = None
    maximum_loadhandling_tilt: float | None = None
    maximum_speed: float | None = None
    maximum_acceleration: float | None = None
    maximum_deceleration: float | None = None
    pick_time: float | None = None
    drop_time: float | None = None
    description: str | None = None


class LoadSpecification(VDAStruct, kw_only=True):
    """Load positions (valid ``lhd`` values) and load sets."""

    load_positions: list[str] | None = None
    load_sets: list[LoadSet] | None = None


class BatteryCharging(VDAStruct, kw_only=True):
    """Charging levels in percent; below ``critical_low_charging_level`` only charge orders."""

    critical_low_charging_level: float | None = None
    minimum_desired_charging_level: float | None = None
    maximum_desired_charging_level: float | None = None
    minimum_charging_time: float | None = None


class MobileRobotConfiguration(VDAStruct, kw_only=True):
    """``mobileRobotConfiguration`` (2.1 ``vehicleConfig`` plus ``batteryCharging``)."""

    versions: list[VersionInfo] | None = None
    network: NetworkConfig | None = None
    battery_charging: BatteryCharging | None = None


class Factsheet(VDAStruct, kw_only=True):
    """``factsheet`` message."""

    header_id: HeaderId
    timestamp: str
    version: str
    manufacturer: str
    serial_number: str
    type_specification: TypeSpecification
    physical_parameters: PhysicalParameters
    protocol_limits: ProtocolLimits
    protocol_features: ProtocolFeatures
    mobile_robot_geometry: MobileRobotGeometry
    load_specification: LoadSpecification
    mobile_robot_configuration: MobileRobotConfiguration | None = None
