"""The VDA 5050 order messages of an execution: which part of the route goes out, and how.

REFERENCE A.1-4 and B.9-12: an order carries nodes and edges in traversal order with sequence
ids 2·i for the route's node i and 2·i−1 for the edge into it; a released prefix (the base) and
an unreleased rest (the horizon). An update repeats the last base node (the stitching node, same
sequence id and content) and goes on from there. The factsheet's `maxArrayLens` limits how many
nodes one message may carry; `base_ahead` limits how far ahead of the vehicle the base reaches.
"""

from dataclasses import dataclass
from typing import Any

import vda5050
from control.execution import LayoutIndex, OrderExecution, StepAction, Window
from vda5050.enums import BlockingType


@dataclass(frozen=True)
class OrderLimits:
    """How much of a route one message carries and how far the base reaches."""

    max_nodes: int | None = None  # factsheet maxArrayLens order.nodes (edges + 1); None = any
    base_ahead: int | None = None  # released nodes ahead of the vehicle; None = the whole route
    min_interval: float = 0.0  # factsheet timing.minOrderInterval, seconds
    # Unreleased nodes sent after the base; None = the rest of the route. The vehicle repeats
    # them in every state (nodeStates, edgeStates), so a whole-route horizon makes each state
    # as long as the route.
    horizon: int | None = None


@dataclass(frozen=True)
class LoadJob:
    """What the pick and drop actions carry."""

    load_id: str
    load_type: str
    pick_station: str
    drop_station: str


def initial_window(route_length: int, limits: OrderLimits) -> Window:
    """The window of a new order: from the vehicle's node (index 0)."""
    return _window(0, route_length, passed=0, limits=limits)


def extension_window(
    route_length: int, released_until: int, passed: int, limits: OrderLimits
) -> Window | None:
    """The window of an update extending the base, or None if nothing more can be released."""
    window = _window(released_until, route_length, passed=passed, limits=limits)
    return window if window.released > released_until else None


def _window(first: int, route_length: int, *, passed: int, limits: OrderLimits) -> Window:
    end = route_length - 1
    last = end if limits.max_nodes is None else min(end, first + max(limits.max_nodes, 2) - 1)
    target = end if limits.base_ahead is None else passed + max(limits.base_ahead, 1)
    released = max(first, min(last, target))
    if limits.horizon is not None:
        last = min(last, released + limits.horizon)
    return Window(first=first, last=last, released=released)


def build_order(
    execution: OrderExecution,
    layout: LayoutIndex,
    window: Window,
    job: LoadJob,
    *,
    max_speed: bool = False,
    loaded_speed: float | None = None,
) -> tuple[list[vda5050.Node], list[vda5050.Edge]]:
    """The nodes and edges of route indices window.first..window.last.

    Node i has sequence id 2·i, the edge into it 2·i−1, so an update's stitching node repeats
    exactly what was sent before (same id, sequence id and actions). Each step of the order is a
    HARD blocking node action at its stop (pick, drop or a custom action), so the vehicle stands
    still while handling the load. With `max_speed`
    each edge carries its speed limit after zones, where it has one, and edges driven with the
    load on board (after a pick, before its drop) at most `loaded_speed`, the factsheet load
    set's `agvSpeedLimit` (REFERENCE J.46).
    """
    route = execution.route
    carrying = _loaded_edges(execution) if loaded_speed is not None else set()
    nodes: list[vda5050.Node] = []
    edges: list[vda5050.Edge] = []
    for index in range(window.first, window.last + 1):
        released = index <= window.released
        if index > window.first:
            edge_id = layout.edges[(route[index - 1], route[index])]
            edges.append(
                vda5050.Edge(
                    edge_id=edge_id,
                    max_speed=_edge_speed(
                        layout.speed_limits.get(edge_id),
                        loaded_speed if index in carrying else None,
                    )
                    if max_speed
                    else None,
                    sequence_id=2 * index - 1,
                    released=released,  # both ends released: the earlier one is
                    start_node_id=route[index - 1],
                    end_node_id=route[index],
                    actions=[],
                )
            )
        place = layout.nodes[route[index]]
        nodes.append(
            vda5050.Node(
                node_id=route[index],
                sequence_id=2 * index,
                released=released,
                node_position=vda5050.NodePosition(
                    x=place.x, y=place.y, theta=place.theta, map_id=place.map_id
                ),
                actions=_node_actions(execution, index, job),
            )
        )
    return nodes, edges


def _loaded_edges(execution: OrderExecution) -> set[int]:
    """Route indices whose incoming edge is driven with a load on board."""
    loaded: set[int] = set()
    carrying, previous = False, 0
    for number, step in enumerate(execution.steps):
        index = execution.stop_index(number)
        if carrying:
            loaded.update(range(previous + 1, index + 1))
        if step.action_type == "pick":
            carrying = True
        elif step.action_type == "drop":
            carrying = False
        previous = index
    return loaded


def _edge_speed(limit: float | None, loaded: float | None) -> float | None:
    given = [speed for speed in (limit, loaded) if speed is not None]
    return min(given) if given else None


def _node_actions(execution: OrderExecution, index: int, job: LoadJob) -> list[vda5050.Action]:
    if execution.kind == "park":
        return []
    if execution.kind == "charge":  # battery charge session: startCharging at the point
        if index != len(execution.route) - 1:
            return []
        action_id = execution.charge_action_id
        return [
            vda5050.Action(
                action_type="startCharging",
                action_id=action_id,
                blocking_type=BlockingType.HARD,
                action_parameters=[],
            )
        ]
    # Every stop at this route index, in step order (two steps may share a node).
    return [
        _step_action(step, job)
        for number, step in enumerate(execution.steps)
        if execution.stop_index(number) == index
    ]


def _step_action(step: StepAction, job: LoadJob) -> vda5050.Action:
    """A stop's node action. Pick and drop carry the station and the load; a custom action
    carries exactly the step's parameters. All are HARD: the vehicle stands while acting."""
    if step.action_type in ("pick", "drop"):
        default = job.pick_station if step.action_type == "pick" else job.drop_station
        values: dict[str, Any] = {
            "stationType": "floor",
            "stationName": step.station or default,
            "loadType": job.load_type or "EPAL",
        }
        if job.load_id:
            values["loadId"] = job.load_id
        values.update(step.parameters)
    else:
        values = dict(step.parameters)
    return vda5050.Action(
        action_type=step.action_type,
        action_id=step.action_id,
        blocking_type=BlockingType.HARD,
        action_parameters=[vda5050.ActionParameter(key=k, value=v) for k, v in values.items()],
    )
