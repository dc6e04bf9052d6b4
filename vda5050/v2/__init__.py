"""msgspec Structs for VDA 5050 2.0.0 and 2.1.0.

2.1.0 is a non-breaking superset of 2.0.0, so one set of Structs serves both: 2.1-only
fields (``Edge.corridor``, ``State.maps``, ``Error.error_hint``,
``Factsheet.vehicle_config``) are optional and omitted when ``None``.
"""

from __future__ import annotations

from typing import TypeAlias

from vda5050.enums import TopicKind
from vda5050.v2.base import (
    BoundingBoxReference,
    HeaderId,
    LoadDimensions,
    NonNegativeInt,
    ParameterValue,
    VDAStruct,
)
from vda5050.v2.factsheet import (
    ActionParameterSpec,
    AgvAction,
    AgvGeometry,
    Envelope2d,
    Envelope3d,
    Factsheet,
    LoadSet,
    LoadSpecification,
    MaxArrayLens,
    MaxStringLens,
    NetworkConfig,
    OptionalParameter,
    PhysicalParameters,
    PolygonPoint,
    ProtocolFeatures,
    ProtocolLimits,
    Timing,
    TypeSpecification,
    VehicleConfig,
    VersionInfo,
    WheelDefinition,
    WheelPosition,
)
from vda5050.v2.messages import Connection, Visualization
from vda5050.v2.order import (
    Action,
    ActionParameter,
    ControlPoint,
    Corridor,
    Edge,
    InstantActions,
    Node,
    NodePosition,
    Order,
    Trajectory,
)
from vda5050.v2.state import (
    ActionState,
    AgvPosition,
    BatteryState,
    EdgeState,
    Error,
    ErrorReference,
    InfoReference,
    Information,
    Load,
    MapState,
    NodeState,
    SafetyState,
    State,
    Velocity,
)

#: Any top-level 2.x message.
Message: TypeAlias = Order | InstantActions | State | Visualization | Connection | Factsheet

#: Struct type of each topic kind.
MESSAGE_TYPES: dict[TopicKind, type[Message]] = {
    TopicKind.ORDER: Order,
    TopicKind.INSTANT_ACTIONS: InstantActions,
    TopicKind.STATE: State,
    TopicKind.VISUALIZATION: Visualization,
    TopicKind.CONNECTION: Connection,
    TopicKind.FACTSHEET: Factsheet,
}

__all__ = [
    "MESSAGE_TYPES",
    "Action",
    "ActionParameter",
    "ActionParameterSpec",
    "ActionState",
    "AgvAction",
    "AgvGeometry",
    "AgvPosition",
    "BatteryState",
    "BoundingBoxReference",
    "Connection",
    "ControlPoint",
    "Corridor",
    "Edge",
    "EdgeState",
    "Envelope2d",
    "Envelope3d",
    "Error",
    "ErrorReference",
    "Factsheet",
    "HeaderId",
    "InfoReference",
    "Information",
    "InstantActions",
    "Load",
    "LoadDimensions",
    "LoadSet",
    "LoadSpecification",
    "MapState",
    "MaxArrayLens",
    "MaxStringLens",
    "Message",
    "NetworkConfig",
    "Node",
    "NodePosition",
    "NodeState",
    "NonNegativeInt",
    "OptionalParameter",
    "Order",
    "ParameterValue",
    "PhysicalParameters",
    "PolygonPoint",
    "ProtocolFeatures",
    "ProtocolLimits",
    "SafetyState",
    "State",
    "Timing",
    "Trajectory",
    "TypeSpecification",
    "VDAStruct",
    "VehicleConfig",
    "Velocity",
    "VersionInfo",
    "Visualization",
    "WheelDefinition",
    "WheelPosition",
]
