"""Small builders for orders, instant actions and vehicles used by the simulator tests."""

from __future__ import annotations

from collections.abc import Callable, Iterable, Mapping, Sequence

from simulator import wire
from simulator.vehicle import StartPose, VehicleConfig, VirtualVehicle
from vda5050 import (
    Action,
    ActionParameter,
    Edge,
    InstantActions,
    Node,
    NodePosition,
    Order,
    State,
    TopicKind,
    encode,
    v3,
)
from vda5050.adapt import instant_actions_v2_to_v3, order_v2_to_v3
from vda5050.enums import ActionStatus, BlockingType

MAP = "demo"

#: A small grid: n1 -(5 m)- n2 -(5 m)- n3, n3 up to n4, n4 right to n5; n9 far away.
POS: dict[str, tuple[float, float]] = {
    "n1": (0.0, 0.0),
    "n2": (5.0, 0.0),
    "n3": (10.0, 0.0),
    "n4": (10.0, 5.0),
    "n5": (15.0, 5.0),
    "n9": (50.0, 50.0),
}

LAYOUT_DICT = {
    "mapId": MAP,
    "nodes": [{"id": nid, "x": x, "y": y} for nid, (x, y) in POS.items()],
    "edges": [
        {"id": "e1", "start": "n1", "end": "n2"},
        {"id": "e2", "start": "n2", "end": "n3"},
        {"id": "e3", "start": "n3", "end": "n4"},
        {"id": "e4", "start": "n4", "end": "n5"},
    ],
    "parking": ["n1", "n3"],
}


def make_vehicle(start: str = "n1", version: str = "2.0.0", **config: object) -> VirtualVehicle:
    """A vehicle standing on ``start`` of the demo map."""
    x, y = POS[start]
    cfg = VehicleConfig(version=version, **config)  # type: ignore[arg-type]
    return VirtualVehicle(cfg, StartPose(MAP, start, x, y), known_nodes=POS)


def action(
    action_type: str,
    action_id: str,
    blocking: BlockingType = BlockingType.HARD,
    **params: str | float,
) -> Action:
    """An action with parameters given as keyword arguments."""
    return Action(
        action_type=action_type,
        action_id=action_id,
        blocking_type=blocking,
        action_parameters=[ActionParameter(key=k, value=v) for k, v in params.items()] or None,
    )


def node(
    seq: int,
    node_id: str,
    released: bool = True,
    actions: Iterable[Action] = (),
    map_id: str = MAP,
    xy: tuple[float, float] | None = None,
) -> Node:
    """An order node positioned at ``POS[node_id]`` (or ``xy``)."""
    x, y = xy if xy is not None else POS[node_id]
    return Node(
        node_id=node_id,
        sequence_id=seq,
        released=released,
        node_position=NodePosition(x=x, y=y, map_id=map_id),
        actions=list(actions),
    )


def edge(seq: int, start: str, end: str, released: bool = True) -> Edge:
    """An order edge between ``start`` and ``end``."""
    return Edge(
        edge_id=f"e-{start}-{end}",
        sequence_id=seq,
        released=released,
        start_node_id=start,
        end_node_id=end,
        actions=[],
    )


def make_order(
    order_id: str,
    path: Sequence[str],
    *,
    released: int | None = None,
    update_id: int = 0,
    first_seq: int = 0,
    actions: Mapping[str, Sequence[Action]] | None = None,
    serial: str = "AGV-1",
) -> Order:
    """An order along ``path``; the first ``released`` nodes (default all) form the base."""
    released = len(path) if released is None else released
    actions = actions or {}
    nodes = [
        node(first_seq + 2 * i, nid, released=i < released, actions=actions.get(nid, ()))
        for i, nid in enumerate(path)
    ]
    edges = [
        edge(first_seq + 2 * i + 1, a, b, released=i + 1 < released)
        for i, (a, b) in enumerate(zip(path, path[1:], strict=False))
    ]
    return Order(
        header_id=0,
        timestamp="2024-01-01T00:00:00.00Z",
        version="2.0.0",
        manufacturer="sim",
        serial_number=serial,
        order_id=order_id,
        order_update_id=update_id,
        nodes=nodes,
        edges=edges,
    )


def instant(*actions: Action) -> InstantActions:
    """An instantActions message."""
    return InstantActions(
        header_id=0,
        timestamp="2024-01-01T00:00:00.00Z",
        version="2.0.0",
        manufacturer="sim",
        serial_number="AGV-1",
        actions=list(actions),
    )


def run(vehicle: VirtualVehicle, seconds: float, dt: float = 0.1) -> list[State]:
    """Tick for ``seconds`` (wall time) and return every state that became due."""
    states = []
    for _ in range(round(seconds / dt)):
        vehicle.tick(dt)
        if vehicle.take_state_due():
            states.append(vehicle.build_state())
    return states


def run_until(
    vehicle: VirtualVehicle,
    predicate: Callable[[VirtualVehicle], bool],
    max_seconds: float = 120.0,
    dt: float = 0.1,
) -> list[State]:
    """Tick until ``predicate`` holds; fail if it never does."""
    states = []
    for _ in range(round(max_seconds / dt)):
        if predicate(vehicle):
            return states
        vehicle.tick(dt)
        if vehicle.take_state_due():
            states.append(vehicle.build_state())
    raise AssertionError(f"condition not reached within {max_seconds} s")


def status(vehicle: VirtualVehicle, action_id: str) -> ActionStatus | None:
    """Current status of an action, None if it is not in actionStates."""
    run_ = vehicle.actions.get(action_id)
    return None if run_ is None else run_.status


def error_types(vehicle: VirtualVehicle) -> list[str]:
    """errorType of every error in the next state."""
    return [e.error_type for e in vehicle.build_state().errors]


def finished(vehicle: VirtualVehicle) -> bool:
    """Order done: nothing pending, every action terminal, standing still."""
    return not vehicle.pending and vehicle.actions.all_terminal and not vehicle.driving


# --- 3.0: messages as a 3.0 master sends them, through the vehicle's message edge ---------


def make_order3(order_id: str, path: Sequence[str], **options: object) -> v3.Order:
    """:func:`make_order` as a 3.0 order (same options; actions keep their blockingType)."""
    order = make_order(order_id, path, **options)  # type: ignore[arg-type]
    order.timestamp = "2024-01-01T00:00:00.000Z"
    return order_v2_to_v3(order, version="3.0.0")


def instant3(*actions: Action) -> v3.InstantActions:
    """A 3.0 instantActions message (blockingType NONE)."""
    message = instant(*actions)
    message.timestamp = "2024-01-01T00:00:00.000Z"
    return instant_actions_v2_to_v3(message, version="3.0.0")


def send3(vehicle: VirtualVehicle, message: v3.Order | v3.InstantActions) -> bool:
    """Deliver a 3.0 message over the wire edge (encode, decode as 3.0, convert)."""
    kind = TopicKind.ORDER if isinstance(message, v3.Order) else TopicKind.INSTANT_ACTIONS
    internal = wire.decode_inbound(kind, encode(message), "3.0.0")
    if isinstance(internal, Order):
        return vehicle.on_order(internal)
    vehicle.on_instant_actions(internal)
    return True


def run3(vehicle: VirtualVehicle, seconds: float, dt: float = 0.1) -> list[v3.State]:
    """Tick for ``seconds`` and return the 3.0 state messages that became due."""
    states: list[v3.State] = []
    for _ in range(round(seconds / dt)):
        vehicle.tick(dt)
        if vehicle.take_state_due():
            states += wire.states(vehicle)  # type: ignore[arg-type]
    return states


def run3_until(
    vehicle: VirtualVehicle, predicate: Callable[[VirtualVehicle], bool], max_seconds: float = 120.0
) -> list[v3.State]:
    """Tick until ``predicate`` holds, collecting 3.0 states; fail if it never does."""
    states: list[v3.State] = []
    for _ in range(round(max_seconds / 0.1)):
        if predicate(vehicle):
            return states
        states += run3(vehicle, 0.1)
    raise AssertionError(f"condition not reached within {max_seconds} s")
