"""Structs of the ``order`` and ``instantActions`` topics (fleet control → mobile robot), 3.0.0.

Differences to 2.x (REFERENCE §6): ``*Descriptor`` instead of ``*Description``, edges without
``startNodeId``/``endNodeId``, ``maximumSpeed`` & co., an ellipse ``allowedDeviationXY``,
``orderDescription``, ``action.retriable`` and the corridor release fields.
"""

from __future__ import annotations

from typing import Annotated

import msgspec

from vda5050.enums import OrientationType
from vda5050.v2.base import HeaderId, NonNegativeInt, VDAStruct
from vda5050.v2.order import ActionParameter, ControlPoint
from vda5050.v3.enums import BlockingType, CorridorReferencePoint, CorridorReleaseLossBehavior

__all__ = [
    "Action",
    "ActionParameter",
    "AllowedDeviationXY",
    "ControlPoint",
    "Corridor",
    "Edge",
    "InstantActions",
    "Node",
    "NodePosition",
    "Order",
    "Trajectory",
]


class Action(VDAStruct, kw_only=True):
    """An action on a node or an edge, or in an ``instantActions`` message.

    ``retriable`` (order actions only): a failure enters RETRIABLE instead of FAILED and waits
    for ``retry``/``skipRetry``. Instant actions always use blockingType NONE.
    """

    action_type: str
    action_id: str
    action_descriptor: str | None = None
    blocking_type: BlockingType
    action_parameters: list[ActionParameter] | None = None
    retriable: bool | None = None


class AllowedDeviationXY(VDAStruct, kw_only=True):
    """Ellipse around a node within which it counts as reached (metres, radians).

    ``a``/``b`` are the semi-axes, ``theta`` the rotation of the ellipse; a circle of radius
    ``r`` (the 2.x number) is ``a = b = r, theta = 0``.
    """

    a: float
    b: float
    theta: float


class NodePosition(VDAStruct, kw_only=True):
    """Position of an order node on a map (2.x ``mapDescription`` is gone)."""

    x: float
    y: float
    theta: float | None = None
    allowed_deviation_xy: AllowedDeviationXY | None = msgspec.field(
        default=None, name="allowedDeviationXY"
    )
    allowed_deviation_theta: float | None = None
    map_id: str


class Node(VDAStruct, kw_only=True):
    """A node of an order. ``actions`` is required on the wire (may be empty)."""

    node_id: str
    sequence_id: NonNegativeInt
    node_descriptor: str | None = None
    released: bool
    node_position: NodePosition | None = None
    actions: list[Action]


class Trajectory(VDAStruct, kw_only=True):
    """A NURBS trajectory. 3.0 makes ``degree`` (default 1, at least 1) and ``knotVector``
    optional."""

    degree: Annotated[int, msgspec.Meta(ge=1)] | None = None
    knot_vector: list[float] | None = None
    control_points: list[ControlPoint]


class Corridor(VDAStruct, kw_only=True):
    """Lateral corridor around an edge; ``releaseRequired`` makes the robot ask for it."""

    left_width: float
    right_width: float
    corridor_reference_point: CorridorReferencePoint | None = None
    release_required: bool | None = None
    release_loss_behavior: CorridorReleaseLossBehavior | None = None


class Edge(VDAStruct, kw_only=True):
    """An edge of an order; it joins the nodes before and after it in the list.

    ``reach_orientation_before_entering`` replaces 2.x ``rotationAllowed`` (with the opposite
    sense); the schema keeps the 2.x name ``maxRotationSpeed``.
    """

    edge_id: str
    sequence_id: NonNegativeInt
    edge_descriptor: str | None = None
    released: bool
    maximum_speed: float | None = None
    maximum_mobile_robot_height: float | None = None
    minimum_load_handling_device_height: float | None = None
    orientation: float | None = None
    orientation_type: OrientationType | None = None
    direction: str | None = None
    reach_orientation_before_entering: bool | None = None
    max_rotation_speed: float | None = None
    trajectory: Trajectory | None = None
    length: float | None = None
    corridor: Corridor | None = None
    actions: list[Action]


class Order(VDAStruct, kw_only=True):
    """``order`` message: a new order (``orderUpdateId`` 0) or an order update."""

    header_id: HeaderId
    timestamp: str
    version: str
    manufacturer: str
    serial_number: str
    order_id: str
    order_update_id: NonNegativeInt
    order_description: str | None = None
    nodes: list[Node]
    edges: list[Edge]


class InstantActions(VDAStruct, kw_only=True):
    """``instantActions`` message: actions to execute immediately (blockingType NONE)."""

    header_id: HeaderId
    timestamp: str
    version: str
    manufacturer: str
    serial_number: str
    actions: list[Action]
