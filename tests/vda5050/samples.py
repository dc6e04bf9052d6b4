"""Realistic sample messages of every topic, for both 2.x versions."""

from __future__ import annotations

import math
from collections.abc import Callable

from vda5050 import (
    Action,
    ActionParameter,
    ActionState,
    ActionStatus,
    AgvPosition,
    BatteryState,
    BlockingType,
    BoundingBoxReference,
    Connection,
    ConnectionState,
    ControlPoint,
    Corridor,
    CorridorRefPoint,
    Edge,
    EdgeState,
    Error,
    ErrorLevel,
    ErrorReference,
    EStop,
    InfoLevel,
    InfoReference,
    Information,
    InstantActions,
    Load,
    LoadDimensions,
    MapState,
    MapStatus,
    Message,
    Node,
    NodePosition,
    NodeState,
    OperatingMode,
    Order,
    OrientationType,
    SafetyState,
    State,
    TopicKind,
    Trajectory,
    Velocity,
    Visualization,
    cancel_order,
    factsheet_request,
    init_position,
    make_action,
    start_pause,
    state_request,
    stop_pause,
)

from .factsheet_sample import make_factsheet
from .support import VERSIONS, header


def pick_action() -> Action:
    """A node action with parameters of every JSON type the schema allows."""
    return Action(
        action_type="pick",
        action_id="pick-1",
        action_description="pick the pallet",
        blocking_type=BlockingType.HARD,
        action_parameters=[
            ActionParameter(key="stationType", value="floor"),
            ActionParameter(key="loadType", value="EPAL"),
            ActionParameter(key="height", value=0.25),
            ActionParameter(key="retries", value=3),
            ActionParameter(key="verify", value=True),
            ActionParameter(key="lhd", value=["front", "rear"]),
            ActionParameter(key="extra", value={"nested": {"list": [1, 2.5, "x", False]}}),
        ],
    )


def make_order(version: str) -> Order:
    """Order with base and horizon, positions, trajectories and actions (2.1: corridor)."""
    v21 = version == "2.1.0"
    nodes = [
        Node(
            node_id="n1",
            sequence_id=0,
            node_description="start",
            released=True,
            node_position=NodePosition(
                x=1.0,
                y=2.0,
                theta=0.0,
                allowed_deviation_xy=0.5,
                allowed_deviation_theta=0.1,
                map_id="hall-1",
                map_description="ground floor",
            ),
            actions=[],
        ),
        Node(
            node_id="n2",
            sequence_id=2,
            released=True,
            node_position=NodePosition(x=5.5, y=2.0, theta=math.pi / 2, map_id="hall-1"),
            actions=[pick_action()],
        ),
        Node(
            node_id="n3",
            sequence_id=4,
            released=False,
            node_position=NodePosition(x=5.5, y=8.0, theta=-math.pi, map_id="hall-1"),
            actions=[make_action("drop", {"loadType": "EPAL"}, BlockingType.SOFT)],
        ),
    ]
    edges = [
        Edge(
            edge_id="e1",
            sequence_id=1,
            edge_description="aisle",
            released=True,
            start_node_id="n1",
            end_node_id="n2",
            max_speed=1.5,
            max_height=2.2,
            min_height=0.1,
            orientation=0.0,
            orientation_type=OrientationType.TANGENTIAL,
            direction="straight",
            rotation_allowed=False,
            max_rotation_speed=0.5,
            length=4.5,
            trajectory=Trajectory(
                degree=2,
                knot_vector=[0.0, 0.0, 0.0, 1.0, 1.0, 1.0],
                control_points=[
                    ControlPoint(x=1.0, y=2.0),
                    ControlPoint(x=3.0, y=2.5, weight=1.5),
                    ControlPoint(x=5.5, y=2.0, weight=1.0),
                ],
            ),
            corridor=(
                Corridor(
                    left_width=0.5,
                    right_width=0.4,
                    corridor_ref_point=CorridorRefPoint.KINEMATICCENTER,
                )
                if v21
                else None
            ),
            actions=[make_action("beep", None)],
        ),
        Edge(
            edge_id="e2",
            sequence_id=3,
            released=False,
            start_node_id="n2",
            end_node_id="n3",
            orientation_type=OrientationType.GLOBAL,
            actions=[],
        ),
    ]
    return Order(
        **header(version),
        order_id="order-42",
        order_update_id=3,
        zone_set_id="zones-a",
        nodes=nodes,
        edges=edges,
    )


INSTANT_ACTION_FACTORIES: dict[str, Callable[[], Action]] = {
    "cancelOrder": cancel_order,
    "startPause": start_pause,
    "stopPause": stop_pause,
    "stateRequest": state_request,
    "factsheetRequest": factsheet_request,
    "initPosition": lambda: init_position(
        x=1.0, y=2.0, theta=0.5, map_id="hall-1", last_node_id="n1"
    ),
}


def make_instant_actions(version: str, actions: list[Action] | None = None) -> InstantActions:
    """instantActions with the given actions (default: every predefined one we send)."""
    if actions is None:
        actions = [factory() for factory in INSTANT_ACTION_FACTORIES.values()]
    return InstantActions(**header(version), actions=actions)


def make_state(version: str) -> State:
    """A state exercising every part: positions, loads, actions, errors, battery, safety."""
    v21 = version == "2.1.0"
    statuses = [s for s in ActionStatus if v21 is False or s is not ActionStatus.PAUSED]
    return State(
        **header(version),
        maps=(
            [
                MapState(map_id="hall-1", map_version="3", map_status=MapStatus.ENABLED),
                MapState(
                    map_id="hall-1",
                    map_version="4",
                    map_description="new racks",
                    map_status=MapStatus.DISABLED,
                ),
            ]
            if v21
            else None
        ),
        order_id="order-42",
        order_update_id=3,
        zone_set_id="zones-a",
        last_node_id="n1",
        last_node_sequence_id=0,
        driving=True,
        paused=False,
        new_base_request=False,
        distance_since_last_node=1.25,
        operating_mode=OperatingMode.AUTOMATIC,
        node_states=[
            NodeState(
                node_id="n2",
                sequence_id=2,
                node_description="pick station",
                released=True,
                node_position=NodePosition(x=5.5, y=2.0, theta=1.5, map_id="hall-1"),
            ),
            NodeState(node_id="n3", sequence_id=4, released=False),
        ],
        edge_states=[
            EdgeState(
                edge_id="e1",
                sequence_id=1,
                edge_description="aisle",
                released=True,
                trajectory=Trajectory(
                    degree=1,
                    knot_vector=[0.0, 0.0, 1.0, 1.0],
                    control_points=[ControlPoint(x=1.0, y=2.0), ControlPoint(x=5.5, y=2.0)],
                ),
            ),
            EdgeState(edge_id="e2", sequence_id=3, released=False),
        ],
        agv_position=AgvPosition(
            x=2.5,
            y=2.1,
            theta=0.05,
            map_id="hall-1",
            map_description="ground floor",
            position_initialized=True,
            localization_score=0.93,
            deviation_range=0.02,
        ),
        velocity=Velocity(vx=1.2, vy=0.0, omega=-0.1),
        loads=[
            Load(
                load_id="PAL-0001",
                load_type="EPAL",
                load_position="front",
                bounding_box_reference=BoundingBoxReference(x=0.0, y=0.0, z=0.1, theta=0.0),
                load_dimensions=LoadDimensions(length=1.2, width=0.8, height=1.0),
                weight=350.0,
            )
        ],
        action_states=[
            ActionState(
                action_id=f"a-{status.value.lower()}",
                action_type="pick",
                action_description="pick the pallet",
                action_status=status,
                result_description="ok" if status is ActionStatus.FINISHED else None,
            )
            for status in statuses
        ],
        battery_state=BatteryState(
            battery_charge=76.5,
            battery_voltage=48.2,
            battery_health=97,
            charging=False,
            reach=12000.0,
        ),
        errors=[
            Error(
                error_type="orderUpdateError",
                error_references=[
                    ErrorReference(reference_key="orderId", reference_value="order-42"),
                    ErrorReference(reference_key="orderUpdateId", reference_value="2"),
                ],
                error_description="orderUpdateId lower than the current one",
                error_hint="send a higher orderUpdateId" if v21 else None,
                error_level=ErrorLevel.WARNING,
            ),
            Error(error_type="laserScannerDirty", error_level=ErrorLevel.FATAL),
        ],
        information=[
            Information(
                info_type="route",
                info_references=[InfoReference(reference_key="nodeId", reference_value="n2")],
                info_description="heading to pick",
                info_level=InfoLevel.INFO,
            ),
            Information(info_type="debug", info_level=InfoLevel.DEBUG),
        ],
        safety_state=SafetyState(e_stop=EStop.NONE, field_violation=False),
    )


def make_visualization(version: str) -> Visualization:
    """A visualization message with pose and velocity."""
    return Visualization(
        **header(version),
        agv_position=AgvPosition(
            x=2.5, y=2.1, theta=0.05, map_id="hall-1", position_initialized=True
        ),
        velocity=Velocity(vx=1.2, vy=0.0, omega=-0.1),
    )


def make_connection(version: str, state: ConnectionState = ConnectionState.ONLINE) -> Connection:
    """A connection message."""
    return Connection(**header(version), connection_state=state)


def samples(version: str) -> list[tuple[TopicKind, Message]]:
    """One or more realistic messages of every kind, for ``version``."""
    result: list[tuple[TopicKind, Message]] = [
        (TopicKind.ORDER, make_order(version)),
        (TopicKind.INSTANT_ACTIONS, make_instant_actions(version)),
        (TopicKind.STATE, make_state(version)),
        (TopicKind.VISUALIZATION, make_visualization(version)),
        (TopicKind.VISUALIZATION, Visualization()),
        (TopicKind.FACTSHEET, make_factsheet(version)),
    ]
    result += [
        (TopicKind.INSTANT_ACTIONS, make_instant_actions(version, [factory()]))
        for factory in INSTANT_ACTION_FACTORIES.values()
    ]
    result += [(TopicKind.CONNECTION, make_connection(version, s)) for s in ConnectionState]
    return result


def sample_id(item: tuple[TopicKind, Message]) -> str:
    """pytest id of a sample."""
    kind, message = item
    if isinstance(message, InstantActions) and len(message.actions) == 1:
        return f"{kind}-{message.actions[0].action_type}"
    if isinstance(message, Connection):
        return f"{kind}-{message.connection_state}"
    if isinstance(message, Visualization) and message.header_id is None:
        return f"{kind}-empty"
    return str(kind)


ALL_SAMPLES = [(version, kind, msg) for version in VERSIONS for kind, msg in samples(version)]
ALL_SAMPLE_IDS = [f"{version}-{sample_id((kind, msg))}" for version, kind, msg in ALL_SAMPLES]
