"""Structs of the ``factsheet`` topic (AGV → master control, retained), 2.0.0 and 2.1.0."""

from __future__ import annotations

from typing import Any

import msgspec

from vda5050.enums import (
    ActionScope,
    AgvClass,
    AgvKinematic,
    BlockingType,
    Support,
    ValueDataType,
    WheelType,
)
from vda5050.v2.base import BoundingBoxReference, HeaderId, LoadDimensions, VDAStruct


class TypeSpecification(VDAStruct, kw_only=True):
    """Vehicle class, kinematics and capabilities.

    ``localization_types``/``navigation_types`` are ``list[str]``: 2.0 allows free text
    (see :class:`~vda5050.enums.LocalizationType`/``NavigationType`` for the 2.1 values).
    """

    series_name: str
    series_description: str | None = None
    agv_kinematic: AgvKinematic
    agv_class: AgvClass
    max_load_mass: float
    localization_types: list[str]
    navigation_types: list[str]


class PhysicalParameters(VDAStruct, kw_only=True):
    """Speeds, accelerations and dimensions.

    ``height_min`` is required by the 2.0 schema, optional in 2.1. ``angular_speed_min``/
    ``angular_speed_max`` are in the 2.1 document but missing from its schema (REFERENCE §7).
    """

    speed_min: float
    speed_max: float
    angular_speed_min: float | None = None
    angular_speed_max: float | None = None
    acceleration_max: float
    deceleration_max: float
    height_min: float | None = None
    height_max: float
    width: float
    length: float


class MaxStringLens(VDAStruct, kw_only=True):
    """Maximum string lengths the vehicle accepts (absent = no limit)."""

    msg_len: int | None = None
    topic_serial_len: int | None = None
    topic_elem_len: int | None = None
    id_len: int | None = None
    id_numerical_only: bool | None = None
    enum_len: int | None = None
    load_id_len: int | None = None


class MaxArrayLens(VDAStruct, kw_only=True):
    """Maximum array lengths the vehicle accepts (absent = no limit).

    Wire names contain dots, so every field names its key explicitly.
    """

    order_nodes: int | None = msgspec.field(default=None, name="order.nodes")
    order_edges: int | None = msgspec.field(default=None, name="order.edges")
    node_actions: int | None = msgspec.field(default=None, name="node.actions")
    edge_actions: int | None = msgspec.field(default=None, name="edge.actions")
    # The upstream key really is "actionsParameters".
    actions_actions_parameters: int | None = msgspec.field(
        default=None, name="actions.actionsParameters"
    )
    instant_actions: int | None = msgspec.field(default=None, name="instantActions")
    trajectory_knot_vector: int | None = msgspec.field(default=None, name="trajectory.knotVector")
    trajectory_control_points: int | None = msgspec.field(
        default=None, name="trajectory.controlPoints"
    )
    state_node_states: int | None = msgspec.field(default=None, name="state.nodeStates")
    state_edge_states: int | None = msgspec.field(default=None, name="state.edgeStates")
    state_loads: int | None = msgspec.field(default=None, name="state.loads")
    state_action_states: int | None = msgspec.field(default=None, name="state.actionStates")
    state_errors: int | None = msgspec.field(default=None, name="state.errors")
    state_information: int | None = msgspec.field(default=None, name="state.information")
    error_error_references: int | None = msgspec.field(default=None, name="error.errorReferences")
    information_info_references: int | None = msgspec.field(
        default=None, name="information.infoReferences"
    )


class Timing(VDAStruct, kw_only=True):
    """Timing limits in seconds."""

    min_order_interval: float
    min_state_interval: float
    default_state_interval: float | None = None
    visualization_interval: float | None = None


class ProtocolLimits(VDAStruct, kw_only=True):
    """Protocol limits; the master must size and throttle messages accordingly."""

    max_string_lens: MaxStringLens
    max_array_lens: MaxArrayLens
    timing: Timing


class OptionalParameter(VDAStruct, kw_only=True):
    """An optional protocol field the vehicle supports or requires (unlisted = unsupported)."""

    parameter: str
    support: Support
    description: str | None = None


class ActionParameterSpec(VDAStruct, kw_only=True):
    """Declaration of one parameter of an action the vehicle supports."""

    key: str
    value_data_type: ValueDataType
    description: str | None = None
    is_optional: bool | None = None


class AgvAction(VDAStruct, kw_only=True):
    """An action type the vehicle supports, with its scopes and parameters.

    The upstream schemas declare ``blockingTypes`` as ``type: array`` with a string
    ``enum``, which no array can satisfy; the document means an array of BlockingType.
    """

    action_type: str
    action_description: str | None = None
    action_scopes: list[ActionScope]
    action_parameters: list[ActionParameterSpec] | None = None
    result_description: str | None = None
    blocking_types: list[BlockingType] | None = None


class ProtocolFeatures(VDAStruct, kw_only=True):
    """Supported optional parameters and actions."""

    optional_parameters: list[OptionalParameter]
    agv_actions: list[AgvAction]


class WheelPosition(VDAStruct, kw_only=True):
    """Wheel position in vehicle coordinates."""

    x: float
    y: float
    theta: float | None = None


class WheelDefinition(VDAStruct, kw_only=True):
    """One wheel of the vehicle."""

    type: WheelType
    is_active_driven: bool
    is_active_steered: bool
    position: WheelPosition
    diameter: float
    width: float
    center_displacement: float | None = None
    constraints: str | None = None


class PolygonPoint(VDAStruct, kw_only=True):
    """Vertex of a 2D envelope."""

    x: float
    y: float


class Envelope2d(VDAStruct, kw_only=True):
    """2D envelope (footprint) polygon of a named set."""

    set: str
    polygon_points: list[PolygonPoint]
    description: str | None = None


class Envelope3d(VDAStruct, kw_only=True):
    """3D envelope of a named set, inline (``data``) or by ``url``.

    ``description`` is a string per 2.0 and the document (the 2.1 schema says integer, a bug).
    """

    set: str
    format: str
    data: dict[str, Any] | None = None
    url: str | None = None
    description: str | None = None


class AgvGeometry(VDAStruct, kw_only=True):
    """Wheels and envelopes of the vehicle."""

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
    max_weight: float | None = None
    min_loadhandling_height: float | None = None
    max_loadhandling_height: float | None = None
    min_loadhandling_depth: float | None = None
    max_loadhandling_depth: float | None = None
    min_loadhandling_tilt: float | None = None
    max_loadhandling_tilt: float | None = None
    agv_speed_limit: float | None = None
    agv_acceleration_limit: float | None = None
    agv_deceleration_limit: float | None = None
    pick_time: float | None = None
    drop_time: float | None = None
    description: str | None = None


class LoadSpecification(VDAStruct, kw_only=True):
    """Load positions (valid ``lhd`` values) and load sets."""

    load_positions: list[str] | None = None
    load_sets: list[LoadSet] | None = None


class VersionInfo(VDAStruct, kw_only=True):
    """A software/hardware version entry of ``vehicleConfig.versions`` (2.1)."""

    key: str
    value: str


class NetworkConfig(VDAStruct, kw_only=True):
    """Network settings of ``vehicleConfig.network`` (2.1)."""

    dns_servers: list[str] | None = None
    local_ip_address: str | None = None
    ntp_servers: list[str] | None = None
    netmask: str | None = None
    default_gateway: str | None = None


class VehicleConfig(VDAStruct, kw_only=True):
    """``vehicleConfig`` (2.1 only)."""

    versions: list[VersionInfo] | None = None
    network: NetworkConfig | None = None


class Factsheet(VDAStruct, kw_only=True):
    """``factsheet`` message.

    ``header_id``/``timestamp`` are required in 2.0 but optional in 2.1, so they default
    to ``None`` here to decode 2.1 factsheets that omit them; always set them when sending.
    ``localization_parameters`` is 2.0 only, ``vehicle_config`` 2.1 only.
    """

    header_id: HeaderId | None = None
    timestamp: str | None = None
    version: str
    manufacturer: str
    serial_number: str
    type_specification: TypeSpecification
    physical_parameters: PhysicalParameters
    protocol_limits: ProtocolLimits
    protocol_features: ProtocolFeatures
    agv_geometry: AgvGeometry
    load_specification: LoadSpecification
    localization_parameters: dict[str, Any] | None = None
    vehicle_config: VehicleConfig | None = None
