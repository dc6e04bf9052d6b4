"""Order validation as a vehicle performs it (REFERENCE §3 A–C seen from the AGV side).

Every check raises :class:`OrderRejected` carrying the 2.x error type the vehicle reports
and, where 3.0 names the case more precisely than its default mapping, the 3.0 error type
(REFERENCE §3 C.18), so the state machine only has to turn the exception into a WARNING error.
"""

from __future__ import annotations

import math
from collections.abc import Collection, Mapping
from dataclasses import dataclass

from simulator.actions import check_action
from vda5050 import Action, Edge, Node, Order, v3
from vda5050.enums import ActionScope, ErrorType

Point = tuple[float, float]


class OrderRejected(Exception):
    """An order (or update) the vehicle refuses; ``error_type`` goes into ``state.errors``.

    ``v3_type`` is the 3.0 error type when it is more specific than the default mapping of
    ``error_type`` (:data:`simulator.wire.V3_ERROR_TYPES`).
    """

    def __init__(self, error_type: str, description: str, v3_type: str | None = None) -> None:
        super().__init__(description)
        self.error_type = error_type
        self.description = description
        self.v3_type = v3_type


@dataclass(slots=True)
class Step:
    """One pending traversal: the edge leading to ``node`` (None for an order's first node)."""

    edge: Edge | None
    node: Node
    target: Point

    @property
    def released(self) -> bool:
        """A step may be driven only when both its edge and its node are released."""
        return self.node.released and (self.edge is None or self.edge.released)

    @property
    def key(self) -> tuple[str, int]:
        """(nodeId, sequenceId) identifying the node of this step."""
        return (self.node.node_id, self.node.sequence_id)


def _invalid(description: str) -> OrderRejected:
    return OrderRejected(ErrorType.VALIDATION_ERROR, description)


def check_structure(order: Order) -> None:
    """Node/edge counts, sequenceIds, edge endpoints and the released prefix."""
    nodes, edges = order.nodes, order.edges
    if not nodes:
        raise _invalid("order has no nodes")
    if len(edges) != len(nodes) - 1:
        raise _invalid(f"order has {len(nodes)} nodes but {len(edges)} edges")
    first = nodes[0].sequence_id
    if first % 2:
        raise _invalid(f"first node sequenceId {first} is odd")
    for i, node in enumerate(nodes):
        if node.sequence_id != first + 2 * i:
            raise _invalid(f"node {node.node_id!r} has sequenceId {node.sequence_id}")
    for i, edge in enumerate(edges):
        if edge.sequence_id != first + 2 * i + 1:
            raise _invalid(f"edge {edge.edge_id!r} has sequenceId {edge.sequence_id}")
        if edge.start_node_id != nodes[i].node_id or edge.end_node_id != nodes[i + 1].node_id:
            raise _invalid(f"edge {edge.edge_id!r} does not join its neighbouring nodes")
    # Interleave node0, edge0, node1, ... : once something is unreleased nothing after it
    # may be released (the base is a prefix).
    flags = [nodes[0].released]
    for edge, node in zip(edges, nodes[1:], strict=True):
        flags += [edge.released, node.released]
    for i, edge in enumerate(edges):
        if edge.released and not (nodes[i].released and nodes[i + 1].released):
            raise _invalid(f"edge {edge.edge_id!r} is released but one of its nodes is not")
    if not flags[0]:
        raise _invalid("first node is not released")
    if any(later and not earlier for earlier, later in zip(flags, flags[1:], strict=False)):
        raise _invalid("released elements do not form a prefix (base followed by horizon)")


def resolve_targets(
    order: Order, maps: Collection[str], fallback: Mapping[str, Point]
) -> list[Point]:
    """Coordinates of every node: nodePosition, else the layout position of that nodeId."""
    targets: list[Point] = []
    for node in order.nodes:
        pos = node.node_position
        if pos is not None:
            if pos.map_id not in maps:
                raise OrderRejected(
                    ErrorType.VALIDATION_ERROR,
                    f"node {node.node_id!r} is on unknown map {pos.map_id!r}",
                    v3.ErrorType.UNKNOWN_MAP_ID,
                )
            if not (math.isfinite(pos.x) and math.isfinite(pos.y)):
                raise _invalid(f"node {node.node_id!r} has a non-finite position")
            targets.append((pos.x, pos.y))
        elif node.node_id in fallback:
            targets.append(fallback[node.node_id])
        else:
            raise _invalid(f"node {node.node_id!r} has no nodePosition and is not in the layout")
    return targets


def check_actions(order: Order, *, skip_first_node: bool, major: int = 2) -> None:
    """Every action must be in the catalogue (of protocol ``major``) for its scope and ids
    must be unique.

    ``skip_first_node``: the stitching node of an update keeps its first-sent content
    (2.1 §6.6.2), so its actions are neither validated nor executed again.
    """
    scoped: list[tuple[ActionScope, Action]] = []
    for i, node in enumerate(order.nodes):
        if not (skip_first_node and i == 0):
            scoped += [(ActionScope.NODE, action) for action in node.actions]
    for edge in order.edges:
        scoped += [(ActionScope.EDGE, action) for action in edge.actions]
    seen: set[str] = set()
    for scope, action in scoped:
        problem = check_action(action, scope, major)
        if problem is None and action.action_id in seen:
            problem = f"duplicate actionId {action.action_id!r}"
        if problem is not None:
            raise OrderRejected(ErrorType.ORDER_ERROR, problem)
        seen.add(action.action_id)


def check_start(
    order: Order, target: Point, position: Point, last_node_id: str, reach: float
) -> None:
    """A new order's first node must be the node we stand on or within reach."""
    first = order.nodes[0]
    if first.node_id == last_node_id and last_node_id:
        return
    allowed = reach
    if first.node_position is not None and first.node_position.allowed_deviation_xy:
        allowed = max(reach, first.node_position.allowed_deviation_xy)
    distance = math.dist(target, position)
    if distance > allowed:
        raise OrderRejected(
            ErrorType.VALIDATION_ERROR,
            f"first node {first.node_id!r} is {distance:.2f} m away (allowed {allowed:.2f} m)",
            v3.ErrorType.START_NODE_OUT_OF_RANGE,
        )


def build_steps(order: Order, targets: list[Point], *, include_first: bool) -> list[Step]:
    """Pending steps of an order; the first node is skipped when it is a stitching node."""
    steps = [Step(None, order.nodes[0], targets[0])] if include_first else []
    for i, edge in enumerate(order.edges):
        steps.append(Step(edge, order.nodes[i + 1], targets[i + 1]))
    return steps
