"""``order`` and ``instantActions`` between 2.x and 3.0 (REFERENCE §6).

2.x → 3.0 (master control sends to a 3.0 robot): edges lose ``startNodeId``/``endNodeId``
(3.0 joins an edge to its neighbours in the list), ``*Description`` → ``*Descriptor``,
``maxSpeed``/``maxHeight``/``minHeight`` → ``maximumSpeed``/``maximumMobileRobotHeight``/
``minimumLoadHandlingDeviceHeight``, ``rotationAllowed`` → ``reachOrientationBeforeEntering``
(its negation: rotation not allowed on the edge = reach the orientation before entering),
``allowedDeviationXY`` radius ``r`` → ellipse ``{a: r, b: r, theta: 0}``, corridor
``KINEMATICCENTER`` → ``KINEMATIC_CENTER``, ``initPosition`` → ``initializePosition``;
``orderDescription`` stays unset, ``retriable`` is set on the actions the caller names (a 2.x
action that came from 3.0 as :class:`RetriableAction` keeps its own); ``zoneSetId`` and
``nodePosition.mapDescription`` are dropped. Instant actions always get blockingType NONE
(REFERENCE §3 E.23). The header is copied; build the 2.x message with the 3.0 version so
headerId counting and the ``.fffZ`` timestamp are right, or pass ``version``.

3.0 → 2.x (a 3.0 robot, or the simulator, reading orders with 2.x logic) is the inverse:
edge start/end node ids come from the neighbouring nodes (``""`` where a malformed order has
none), an ellipse becomes its smaller semi-axis (never accepting a position the ellipse
excludes), blockingType SINGLE stays the string ``"SINGLE"``, an action with ``retriable``
becomes a :class:`RetriableAction` (a 2.x Action that keeps the flag for the vehicle side,
REFERENCE §3 E.27), the 3.0-only ``orderDescription`` and corridor release fields are dropped.
Round trips are lossless for messages without those fields.
"""

from __future__ import annotations

from collections.abc import Collection

from vda5050 import v2, v3
from vda5050.adapt.common import action_type_v2, action_type_v3, to_v2, to_v3
from vda5050.enums import BlockingType, CorridorRefPoint

__all__ = [
    "RetriableAction",
    "instant_actions_v2_to_v3",
    "instant_actions_v3_to_v2",
    "order_v2_to_v3",
    "order_v3_to_v2",
]


class RetriableAction(v2.Action, kw_only=True):
    """A 3.0 order action read with 2.x logic that keeps its ``retriable`` flag: a failure
    enters RETRIABLE (2.x model: PAUSED, marked) and waits for ``retry``/``skipRetry``.
    Only ever built from a 3.0 message; never sent to a 2.x vehicle."""

    retriable: bool | None = None


def order_v2_to_v3(
    order: v2.Order, *, version: str | None = None, retriable: Collection[str] = ()
) -> v3.Order:
    """A 2.x order (or update) as 3.0 ``order``; ``version`` overrides the header version,
    the node and edge actions whose ids are in ``retriable`` get ``retriable: true``."""
    return v3.Order(
        header_id=order.header_id,
        timestamp=order.timestamp,
        version=order.version if version is None else version,
        manufacturer=order.manufacturer,
        serial_number=order.serial_number,
        order_id=order.order_id,
        order_update_id=order.order_update_id,
        nodes=[_node_to_v3(node, retriable) for node in order.nodes],
        edges=[_edge_to_v3(edge, retriable) for edge in order.edges],
    )


def order_v3_to_v2(order: v3.Order) -> v2.Order:
    """A 3.0 order as 2.x ``order`` (edge ``i`` joins nodes ``i`` and ``i + 1``)."""
    node_ids = [node.node_id for node in order.nodes]

    def node_id(index: int) -> str:
        return node_ids[index] if 0 <= index < len(node_ids) else ""

    return v2.Order(
        header_id=order.header_id,
        timestamp=order.timestamp,
        version=order.version,
        manufacturer=order.manufacturer,
        serial_number=order.serial_number,
        order_id=order.order_id,
        order_update_id=order.order_update_id,
        nodes=[_node_to_v2(node) for node in order.nodes],
        edges=[_edge_to_v2(edge, node_id(i), node_id(i + 1)) for i, edge in enumerate(order.edges)],
    )


def instant_actions_v2_to_v3(
    message: v2.InstantActions, *, version: str | None = None
) -> v3.InstantActions:
    """2.x instant actions as 3.0: blockingType NONE, ``initializePosition``."""
    return v3.InstantActions(
        header_id=message.header_id,
        timestamp=message.timestamp,
        version=message.version if version is None else version,
        manufacturer=message.manufacturer,
        serial_number=message.serial_number,
        actions=[action_to_v3(action, instant=True) for action in message.actions],
    )


def instant_actions_v3_to_v2(message: v3.InstantActions) -> v2.InstantActions:
    """3.0 instant actions as 2.x (``initializePosition`` → ``initPosition``)."""
    return v2.InstantActions(
        header_id=message.header_id,
        timestamp=message.timestamp,
        version=message.version,
        manufacturer=message.manufacturer,
        serial_number=message.serial_number,
        actions=[action_to_v2(action) for action in message.actions],
    )


def action_to_v3(
    action: v2.Action, *, instant: bool = False, retriable: bool | None = None
) -> v3.Action:
    """One 2.x action in 3.0 shape (``instant``: blockingType NONE; ``retriable`` as given,
    else the flag a :class:`RetriableAction` kept)."""
    if retriable is None and not instant:
        retriable = getattr(action, "retriable", None)
    return v3.Action(
        action_type=action_type_v3(action.action_type),
        action_id=action.action_id,
        action_descriptor=action.action_description,
        blocking_type=(
            v3.BlockingType.NONE if instant else to_v3(v3.BlockingType, action.blocking_type)
        ),
        action_parameters=None
        if action.action_parameters is None
        else list(action.action_parameters),
        retriable=retriable,
    )


def action_to_v2(action: v3.Action) -> v2.Action:
    """One 3.0 action in 2.x shape (SINGLE kept as a string, ``retriable`` kept by a
    :class:`RetriableAction`)."""
    if action.retriable is not None:
        return RetriableAction(
            action_type=action_type_v2(action.action_type),
            action_id=action.action_id,
            action_description=action.action_descriptor,
            blocking_type=to_v2(BlockingType, action.blocking_type),
            action_parameters=None
            if action.action_parameters is None
            else list(action.action_parameters),
            retriable=action.retriable,
        )
    return v2.Action(
        action_type=action_type_v2(action.action_type),
        action_id=action.action_id,
        action_description=action.action_descriptor,
        blocking_type=to_v2(BlockingType, action.blocking_type),
        action_parameters=None
        if action.action_parameters is None
        else list(action.action_parameters),
    )


def trajectory_to_v3(trajectory: v2.Trajectory | None) -> v3.Trajectory | None:
    """2.x trajectory in 3.0 shape (same fields)."""
    if trajectory is None:
        return None
    return v3.Trajectory(
        degree=trajectory.degree,
        knot_vector=list(trajectory.knot_vector),
        control_points=list(trajectory.control_points),
    )


def trajectory_to_v2(trajectory: v3.Trajectory | None) -> v2.Trajectory | None:
    """3.0 trajectory in 2.x shape; a missing ``knotVector`` becomes the clamped uniform one,
    a missing ``degree`` 1. ``None`` if there are too few control points for the degree."""
    if trajectory is None:
        return None
    # Clamped to >= 1: the knot vector below is sized by the degree, never by hostile input.
    degree = max(trajectory.degree or 1, 1)
    points = list(trajectory.control_points)
    knots = trajectory.knot_vector
    if knots is None:
        inner = len(points) - degree
        if inner < 1:
            return None
        knots = [0.0] * (degree + 1) + [i / inner for i in range(1, inner)] + [1.0] * (degree + 1)
    return v2.Trajectory(degree=degree, knot_vector=list(knots), control_points=points)


def _marked(action: v2.Action, retriable: Collection[str]) -> v3.Action:
    return action_to_v3(action, retriable=True if action.action_id in retriable else None)


def _node_to_v3(node: v2.Node, retriable: Collection[str] = ()) -> v3.Node:
    pos = node.node_position
    position = None
    if pos is not None:
        radius = pos.allowed_deviation_xy
        position = v3.NodePosition(
            x=pos.x,
            y=pos.y,
            theta=pos.theta,
            allowed_deviation_xy=(
                None if radius is None else v3.AllowedDeviationXY(a=radius, b=radius, theta=0.0)
            ),
            allowed_deviation_theta=pos.allowed_deviation_theta,
            map_id=pos.map_id,
        )
    return v3.Node(
        node_id=node.node_id,
        sequence_id=node.sequence_id,
        node_descriptor=node.node_description,
        released=node.released,
        node_position=position,
        actions=[_marked(action, retriable) for action in node.actions],
    )


def _node_to_v2(node: v3.Node) -> v2.Node:
    pos = node.node_position
    position = None
    if pos is not None:
        ellipse = pos.allowed_deviation_xy
        position = v2.NodePosition(
            x=pos.x,
            y=pos.y,
            theta=pos.theta,
            allowed_deviation_xy=None if ellipse is None else min(ellipse.a, ellipse.b),
            allowed_deviation_theta=pos.allowed_deviation_theta,
            map_id=pos.map_id,
        )
    return v2.Node(
        node_id=node.node_id,
        sequence_id=node.sequence_id,
        node_description=node.node_descriptor,
        released=node.released,
        node_position=position,
        actions=[action_to_v2(action) for action in node.actions],
    )


def _edge_to_v3(edge: v2.Edge, retriable: Collection[str] = ()) -> v3.Edge:
    corridor = edge.corridor
    return v3.Edge(
        edge_id=edge.edge_id,
        sequence_id=edge.sequence_id,
        edge_descriptor=edge.edge_description,
        released=edge.released,
        maximum_speed=edge.max_speed,
        maximum_mobile_robot_height=edge.max_height,
        minimum_load_handling_device_height=edge.min_height,
        orientation=edge.orientation,
        orientation_type=edge.orientation_type,
        direction=edge.direction,
        reach_orientation_before_entering=(
            None if edge.rotation_allowed is None else not edge.rotation_allowed
        ),
        max_rotation_speed=edge.max_rotation_speed,
        trajectory=trajectory_to_v3(edge.trajectory),
        length=edge.length,
        corridor=(
            None
            if corridor is None
            else v3.Corridor(
                left_width=corridor.left_width,
                right_width=corridor.right_width,
                corridor_reference_point=(
                    None
                    if corridor.corridor_ref_point is None
                    else to_v3(v3.CorridorReferencePoint, corridor.corridor_ref_point)
                ),
            )
        ),
        actions=[_marked(action, retriable) for action in edge.actions],
    )


def _edge_to_v2(edge: v3.Edge, start_node_id: str, end_node_id: str) -> v2.Edge:
    corridor = edge.corridor
    reach = edge.reach_orientation_before_entering
    return v2.Edge(
        edge_id=edge.edge_id,
        sequence_id=edge.sequence_id,
        edge_description=edge.edge_descriptor,
        released=edge.released,
        start_node_id=start_node_id,
        end_node_id=end_node_id,
        max_speed=edge.maximum_speed,
        max_height=edge.maximum_mobile_robot_height,
        min_height=edge.minimum_load_handling_device_height,
        orientation=edge.orientation,
        orientation_type=edge.orientation_type,
        direction=edge.direction,
        rotation_allowed=None if reach is None else not reach,
        max_rotation_speed=edge.max_rotation_speed,
        trajectory=trajectory_to_v2(edge.trajectory),
        length=edge.length,
        corridor=(
            None
            if corridor is None
            else v2.Corridor(
                left_width=corridor.left_width,
                right_width=corridor.right_width,
                corridor_ref_point=(
                    None
                    if corridor.corridor_reference_point is None
                    else to_v2(CorridorRefPoint, corridor.corridor_reference_point)
                ),
            )
        ),
        actions=[action_to_v2(action) for action in edge.actions],
    )
