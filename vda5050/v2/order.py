"""Structs of the ``order`` topic (master control → AGV), 2.0.0 and 2.1.0."""

from __future__ import annotations

import msgspec

from vda5050.enums import BlockingType, CorridorRefPoint, OrientationType
from vda5050.v2.base import HeaderId, NonNegativeInt, ParameterValue, VDAStruct


class ActionParameter(VDAStruct, kw_only=True):
    """One ``key``/``value`` pair of an action."""

    key: str
    value: ParameterValue


class Action(VDAStruct, kw_only=True):
    """An action on a node, an edge or in an ``instantActions`` message."""

    action_type: str
    action_id: str
    action_description: str | None = None
    blocking_type: BlockingType
    action_parameters: list[ActionParameter] | None = None


class NodePosition(VDAStruct, kw_only=True):
    """Position of a node on a map (order nodes, optionally echoed in ``nodeStates``)."""

    x: float
    y: float
    theta: float | None = None
    # rename="camel" would produce "allowedDeviationXy"; the wire name keeps "XY".
    allowed_deviation_xy: float | None = msgspec.field(default=None, name="allowedDeviationXY")
    allowed_deviation_theta: float | None = None
    map_id: str
    map_description: str | None = None


class Node(VDAStruct, kw_only=True):
    """A node of an order. ``actions`` is required on the wire (may be empty)."""

    node_id: str
    sequence_id: NonNegativeInt
    node_description: str | None = None
    released: bool
    node_position: NodePosition | None = None
    actions: list[Action]


class ControlPoint(VDAStruct, kw_only=True):
    """A NURBS control point; ``weight`` defaults to 1.0 on the vehicle when absent."""

    x: float
    y: float
    weight: float | None = None


class Trajectory(VDAStruct, kw_only=True, omit_defaults=False):
    """A NURBS trajectory (order edges and ``edgeStates``).

    ``degree`` defaults to 1 (the documented default) so a 2.0 state that omits it still
    decodes, and ``omit_defaults=False`` so we always send it: the order schema requires it.
    """

    degree: int = 1
    knot_vector: list[float]
    control_points: list[ControlPoint]


class Corridor(VDAStruct, kw_only=True):
    """Lateral corridor around an edge (2.1 only; omit it rather than sending zeros)."""

    left_width: float
    right_width: float
    corridor_ref_point: CorridorRefPoint | None = None


class Edge(VDAStruct, kw_only=True):
    """An edge of an order. ``actions`` is required on the wire (may be empty)."""

    edge_id: str
    sequence_id: NonNegativeInt
    edge_description: str | None = None
    released: bool
    start_node_id: str
    end_node_id: str
    max_speed: float | None = None
    max_height: float | None = None
    min_height: float | None = None
    orientation: float | None = None
    orientation_type: OrientationType | None = None
    direction: str | None = None
    rotation_allowed: bool | None = None
    max_rotation_speed: float | None = None
    trajectory: Trajectory | None = None
    length: float | None = None
    corridor: Corridor | None = None
    actions: list[Action]


class Order(VDAStruct, kw_only=True):
    """``order`` message: a new order or an order update."""

    header_id: HeaderId
    timestamp: str
    version: str
    manufacturer: str
    serial_number: str
    order_id: str
    order_update_id: NonNegativeInt
    zone_set_id: str | None = None
    nodes: list[Node]
    edges: list[Edge]


class InstantActions(VDAStruct, kw_only=True):
    """``instantActions`` message: actions to execute immediately."""

    header_id: HeaderId
    timestamp: str
    version: str
    manufacturer: str
    serial_number: str
    actions: list[Action]
