"""Realistic VDA 5050 3.0.0 sample messages of all eight topics."""

from __future__ import annotations

import math
from typing import Any

from vda5050 import TopicKind, v3
from vda5050.enums import InfoLevel, MapStatus, OrientationType, Support

from .support import MANUFACTURER, SERIAL

V3 = "3.0.0"
TIMESTAMP_V3 = "2024-03-11T11:40:03.123Z"


def header3(header_id: int = 7) -> dict[str, Any]:
    """Header keyword arguments of a 3.0 sample."""
    return {
        "header_id": header_id,
        "timestamp": TIMESTAMP_V3,
        "version": V3,
        "manufacturer": MANUFACTURER,
        "serial_number": SERIAL,
    }


def pick3() -> v3.Action:
    """A retriable SINGLE node action with parameters of every JSON type."""
    return v3.Action(
        action_type="pick",
        action_id="pick-1",
        action_descriptor="pick the pallet",
        blocking_type=v3.BlockingType.SINGLE,
        action_parameters=[
            v3.ActionParameter(key="loadType", value="EPAL"),
            v3.ActionParameter(key="height", value=0.25),
            v3.ActionParameter(key="retries", value=3),
            v3.ActionParameter(key="verify", value=True),
            v3.ActionParameter(key="lhd", value=["front", "rear"]),
            v3.ActionParameter(key="extra", value={"nested": [1, 2.5, "x"]}),
        ],
        retriable=True,
    )


def trajectory3() -> v3.Trajectory:
    """A degree-2 NURBS with explicit knots."""
    return v3.Trajectory(
        degree=2,
        knot_vector=[0.0, 0.0, 0.0, 1.0, 1.0, 1.0],
        control_points=[
            v3.ControlPoint(x=1.0, y=2.0),
            v3.ControlPoint(x=3.0, y=2.5, weight=1.5),
            v3.ControlPoint(x=5.5, y=2.0),
        ],
    )


def make_order3() -> v3.Order:
    """A new 3.0 order (orderUpdateId 0) with base, horizon, corridor and ellipse."""
    nodes = [
        v3.Node(
            node_id="n1",
            sequence_id=0,
            node_descriptor="start",
            released=True,
            node_position=v3.NodePosition(
                x=1.0,
                y=2.0,
                theta=0.0,
                allowed_deviation_xy=v3.AllowedDeviationXY(a=0.5, b=0.3, theta=0.2),
                allowed_deviation_theta=0.1,
                map_id="hall-1",
            ),
            actions=[],
        ),
        v3.Node(
            node_id="n2",
            sequence_id=2,
            released=True,
            node_position=v3.NodePosition(x=5.5, y=2.0, theta=math.pi / 2, map_id="hall-1"),
            actions=[pick3()],
        ),
        v3.Node(node_id="n3", sequence_id=4, released=False, actions=[]),
    ]
    edges = [
        v3.Edge(
            edge_id="e1",
            sequence_id=1,
            edge_descriptor="aisle",
            released=True,
            maximum_speed=1.5,
            maximum_mobile_robot_height=2.2,
            minimum_load_handling_device_height=0.1,
            orientation=0.0,
            orientation_type=OrientationType.TANGENTIAL,
            direction="straight",
            reach_orientation_before_entering=True,
            max_rotation_speed=0.5,
            trajectory=trajectory3(),
            length=4.5,
            corridor=v3.Corridor(
                left_width=0.5,
                right_width=0.4,
                corridor_reference_point=v3.CorridorReferencePoint.KINEMATIC_CENTER,
                release_required=True,
                release_loss_behavior=v3.CorridorReleaseLossBehavior.STOP,
            ),
            actions=[],
        ),
        v3.Edge(edge_id="e2", sequence_id=3, released=False, actions=[]),
    ]
    return v3.Order(
        **header3(),
        order_id="order-42",
        order_update_id=0,
        order_description="pallet to dock",
        nodes=nodes,
        edges=edges,
    )


def make_instant_actions3() -> v3.InstantActions:
    """Instant actions, all blockingType NONE."""
    actions = [
        v3.Action(action_type="cancelOrder", action_id="c1", blocking_type=v3.BlockingType.NONE),
        v3.Action(
            action_type="initializePosition",
            action_id="i1",
            blocking_type=v3.BlockingType.NONE,
            action_parameters=[
                v3.ActionParameter(key="x", value=1.0),
                v3.ActionParameter(key="y", value=2.0),
                v3.ActionParameter(key="theta", value=0.5),
                v3.ActionParameter(key="mapId", value="hall-1"),
                v3.ActionParameter(key="lastNodeId", value="n1"),
            ],
        ),
        v3.Action(
            action_type="retry",
            action_id="r1",
            action_descriptor="retry the pick",
            blocking_type=v3.BlockingType.NONE,
            action_parameters=[v3.ActionParameter(key="actionId", value="pick-1")],
        ),
    ]
    return v3.InstantActions(**header3(), actions=actions)


def action_state3(action_id: str, status: v3.ActionStatus, **extra: Any) -> v3.ActionState:
    """An action state with a type and, for terminal states, a result."""
    return v3.ActionState(
        action_id=action_id,
        action_type=str(extra.get("action_type", "pick")),
        action_status=status,
        action_result=extra.get("result"),
    )


def make_state3(**changes: object) -> v3.State:
    """A 3.0 state exercising every part; ``changes`` replace fields."""
    state = v3.State(
        **header3(),
        maps=[
            v3.MapState(map_id="hall-1", map_version="3", map_status=MapStatus.ENABLED),
            v3.MapState(
                map_id="hall-1",
                map_version="4",
                map_descriptor="new racks",
                map_status=MapStatus.DISABLED,
            ),
        ],
        zone_sets=[
            v3.ZoneSetState(
                zone_set_id="zones-a", map_id="hall-1", zone_set_status=v3.ZoneSetStatus.ENABLED
            ),
        ],
        order_id="order-42",
        order_update_id=3,
        last_node_id="n1",
        last_node_sequence_id=0,
        node_states=[
            v3.NodeState(
                node_id="n2",
                sequence_id=2,
                node_descriptor="pick station",
                released=True,
                node_position=v3.NodeStatePosition(x=5.5, y=2.0, theta=1.5, map_id="hall-1"),
            ),
            v3.NodeState(node_id="n3", sequence_id=4, released=False),
        ],
        edge_states=[
            v3.EdgeState(
                edge_id="e1",
                sequence_id=1,
                edge_descriptor="aisle",
                released=True,
                trajectory=trajectory3(),
            ),
            v3.EdgeState(edge_id="e2", sequence_id=3, released=False),
        ],
        mobile_robot_position=v3.MobileRobotPosition(
            x=2.5,
            y=2.1,
            theta=0.05,
            map_id="hall-1",
            localized=True,
            localization_score=0.93,
            deviation_range=0.02,
        ),
        velocity=v3.Velocity(vx=1.2, vy=0.0, omega=-0.1),
        loads=[
            v3.Load(
                load_id="PAL-0001",
                load_type="EPAL",
                load_position="front",
                bounding_box_reference=v3.BoundingBoxReference(x=0.0, y=0.0, z=0.1, theta=0.0),
                load_dimensions=v3.LoadDimensions(length=1.2, width=0.8, height=1.0),
                weight=350.0,
            )
        ],
        driving=True,
        paused=False,
        new_base_request=False,
        distance_since_last_node=1.25,
        action_states=[
            action_state3("pick-1", v3.ActionStatus.RETRIABLE, result="gripper blocked"),
            action_state3("drop-1", v3.ActionStatus.WAITING, action_type="drop"),
        ],
        instant_action_states=[
            action_state3("c0", v3.ActionStatus.FINISHED, action_type="cancelOrder"),
            action_state3("i0", v3.ActionStatus.FINISHED, action_type="initializePosition"),
        ],
        power_supply=v3.PowerSupply(
            state_of_charge=76.5,
            battery_voltage=48.2,
            battery_current=-12.5,
            battery_health=97.0,
            charging=False,
            range=12000.0,
        ),
        operating_mode=v3.OperatingMode.AUTOMATIC,
        errors=[
            v3.Error(
                error_type="OUTDATED_ORDER_UPDATE",
                error_references=[
                    v3.ErrorReference(reference_key="orderId", reference_value="order-42"),
                    v3.ErrorReference(reference_key="orderUpdateId", reference_value="2"),
                ],
                error_description="orderUpdateId lower than the current one",
                error_hint="send a higher orderUpdateId",
                error_level=v3.ErrorLevel.WARNING,
            ),
            v3.Error(error_type="INSTANT_ACTION_STATES_FULL", error_level=v3.ErrorLevel.URGENT),
            v3.Error(error_type="NODE_UNREACHABLE", error_level=v3.ErrorLevel.CRITICAL),
            v3.Error(error_type="LOCALIZATION_ERROR", error_level=v3.ErrorLevel.FATAL),
        ],
        information=[
            v3.Information(
                info_type="route",
                info_references=[v3.InfoReference(reference_key="nodeId", reference_value="n2")],
                info_descriptor="heading to pick",
                info_level=InfoLevel.INFO,
            ),
        ],
        safety_state=v3.SafetyState(
            active_emergency_stop=v3.ActiveEmergencyStop.NONE, field_violation=False
        ),
    )
    for name, value in changes.items():
        setattr(state, name, value)
    return state


def make_state3_full() -> v3.State:
    """:func:`make_state3` plus every 3.0-only part (requests, paths, translations)."""
    state = make_state3()
    state.zone_requests = [
        v3.ZoneRequest(
            request_id="zr1",
            request_type=v3.ZoneRequestType.ACCESS,
            zone_id="z1",
            zone_set_id="zones-a",
            request_status=v3.RequestStatus.REQUESTED,
        ),
        v3.ZoneRequest(
            request_id="zr2",
            request_type=v3.ZoneRequestType.REPLANNING,
            zone_id="z2",
            zone_set_id="zones-a",
            request_status=v3.RequestStatus.GRANTED,
            trajectory=trajectory3(),
        ),
    ]
    state.edge_requests = [
        v3.EdgeRequest(
            request_id="er1",
            request_type=v3.EdgeRequestType.CORRIDOR,
            edge_id="e1",
            sequence_id=1,
            request_status=v3.RequestStatus.EXPIRED,
        )
    ]
    state.planned_path = v3.PlannedPath(trajectory=trajectory3(), traversed_nodes=["n1", "n2"])
    state.intermediate_path = v3.IntermediatePath(
        polyline=[
            v3.PolylinePoint(x=2.6, y=2.1, theta=0.0, eta="2024-03-11T11:40:04.000Z"),
            v3.PolylinePoint(x=3.0, y=2.2, eta="2024-03-11T11:40:05.000Z"),
        ]
    )
    state.zone_action_states = [action_state3("za1", v3.ActionStatus.RUNNING, action_type="beep")]
    state.errors[0].error_description_translations = [
        v3.Translation(translation_key="de", translation_value="orderUpdateId zu klein")
    ]
    state.errors[0].error_hint_translations = [
        v3.Translation(translation_key="de", translation_value="höhere orderUpdateId senden")
    ]
    return state


def make_visualization3() -> v3.Visualization:
    """A visualization with pose, velocity and both paths."""
    return v3.Visualization(
        **header3(),
        reference_state_header_id=6,
        planned_path=v3.PlannedPath(trajectory=trajectory3()),
        intermediate_path=v3.IntermediatePath(
            polyline=[v3.PolylinePoint(x=2.6, y=2.1, eta="2024-03-11T11:40:04.000Z")]
        ),
        mobile_robot_position=v3.MobileRobotPosition(
            x=2.5, y=2.1, theta=0.05, map_id="hall-1", localized=True
        ),
        velocity=v3.Velocity(vx=1.2, vy=0.0, omega=-0.1),
    )


def make_connection3(state: v3.ConnectionState) -> v3.Connection:
    """A connection message."""
    return v3.Connection(**header3(), connection_state=state)


def make_zone_set3() -> v3.ZoneSet:
    """A zone set with one zone of every type (each with its required fields)."""
    square = [v3.Vertex(x=0.0, y=0.0), v3.Vertex(x=1.0, y=0.0), v3.Vertex(x=1.0, y=1.0)]
    extra: dict[v3.ZoneType, dict[str, Any]] = {
        v3.ZoneType.RELEASE: {"release_loss_behavior": v3.ZoneReleaseLossBehavior.EVACUATE},
        v3.ZoneType.SPEED_LIMIT: {"maximum_speed": 0.3},
        v3.ZoneType.ACTION: {
            "entry_actions": [
                v3.ZoneAction(
                    action_type="beep",
                    blocking_type=v3.BlockingType.NONE,
                    action_parameters=[v3.ActionParameter(key="volume", value=3)],
                    retriable=False,
                )
            ],
            "during_actions": [],
            "exit_actions": [],
        },
        v3.ZoneType.PRIORITY: {"priority_factor": 0.5},
        v3.ZoneType.PENALTY: {"penalty_factor": 1.0},
        v3.ZoneType.DIRECTED: {
            "direction": 1.57,
            "directed_limitation": v3.DirectedLimitation.STRICT,
        },
        v3.ZoneType.BIDIRECTED: {
            "direction": 0.0,
            "bidirected_limitation": v3.BidirectedLimitation.RESTRICTED,
        },
    }
    zones = [
        v3.Zone(
            zone_id=f"z-{zone_type.value.lower()}",
            zone_type=zone_type,
            zone_descriptor=f"a {zone_type} zone",
            vertices=square,
            **extra.get(zone_type, {}),
        )
        for zone_type in v3.ZoneType
    ]
    return v3.ZoneSet(
        **header3(),
        zone_set=v3.ZoneSetDefinition(
            map_id="hall-1", zone_set_id="zones-a", zone_set_descriptor="aisles", zones=zones
        ),
    )


def make_responses3() -> v3.Responses:
    """Answers of every grant type; only GRANTED carries a lease."""
    return v3.Responses(
        **header3(),
        responses=[
            v3.Response(
                request_id=f"r-{grant.value.lower()}",
                grant_type=grant,
                lease_expiry="2024-03-11T11:45:00.000Z" if grant is v3.GrantType.GRANTED else None,
            )
            for grant in v3.GrantType
        ],
    )


def make_factsheet3() -> v3.Factsheet:
    """A complete 3.0 factsheet."""
    return v3.Factsheet(
        **header3(),
        type_specification=v3.TypeSpecification(
            series_name="Carrier X",
            series_description="test carrier",
            mobile_robot_kinematics=v3.MobileRobotKinematics.DIFFERENTIAL,
            mobile_robot_class=v3.MobileRobotClass.CARRIER,
            maximum_load_mass=500.0,
            localization_types=["NATURAL", "REFLECTOR"],
            navigation_types=[v3.NavigationType.FREELY_NAVIGATING],
            supported_zones=[v3.ZoneType.BLOCKED, v3.ZoneType.SPEED_LIMIT],
        ),
        physical_parameters=v3.PhysicalParameters(
            minimum_speed=0.0,
            maximum_speed=2.0,
            minimum_angular_speed=0.0,
            maximum_angular_speed=1.0,
            maximum_acceleration=0.5,
            maximum_deceleration=0.8,
            minimum_height=0.3,
            maximum_height=0.5,
            width=0.8,
            length=1.2,
        ),
        protocol_limits=v3.ProtocolLimits(
            maximum_string_lengths=v3.MaximumStringLengths(
                maximum_message_length=100_000,
                maximum_topic_serial_length=32,
                maximum_topic_element_length=32,
                maximum_id_length=64,
                id_numerical_only=False,
                maximum_load_id_length=32,
            ),
            maximum_array_lengths=v3.MaximumArrayLengths(
                order_nodes=50,
                order_edges=49,
                actions_actions_parameters=10,
                zone_set_zones=20,
                state_instant_action_states=100,
            ),
            timing=v3.Timing(
                minimum_order_interval=0.5,
                minimum_state_interval=0.1,
                default_state_interval=30.0,
                visualization_interval=0.2,
            ),
        ),
        protocol_features=v3.ProtocolFeatures(
            optional_parameters=[
                v3.OptionalParameter(parameter="order.edges.trajectory", support=Support.SUPPORTED)
            ],
            mobile_robot_actions=[
                v3.MobileRobotAction(
                    action_type="initializePosition",
                    action_description="set the pose",
                    action_scopes=[v3.ActionScope.INSTANT, v3.ActionScope.NODE],
                    action_parameters=[
                        v3.ActionParameterSpec(
                            key="x", value_data_type=v3.ValueDataType.NUMBER, is_optional=False
                        ),
                    ],
                    action_result="pose set",
                    blocking_types=[v3.BlockingType.NONE, v3.BlockingType.HARD],
                    pause_allowed=False,
                    cancel_allowed=False,
                ),
                v3.MobileRobotAction(
                    action_type="detectObject",
                    action_scopes=[v3.ActionScope.NODE, v3.ActionScope.ZONE],
                    blocking_types=[v3.BlockingType.SINGLE],
                    pause_allowed=True,
                    cancel_allowed=True,
                ),
            ],
        ),
        mobile_robot_geometry=v3.MobileRobotGeometry(
            wheel_definitions=[
                v3.WheelDefinition(
                    type=v3.WheelType.DRIVE,
                    is_active_driven=True,
                    is_active_steered=False,
                    position=v3.WheelPosition(x=0.0, y=0.3),
                    diameter=0.2,
                    width=0.05,
                )
            ],
            envelopes2d=[
                v3.Envelope2d(
                    envelope2d_id="default",
                    vertices=[
                        v3.Vertex(x=0.6, y=0.4),
                        v3.Vertex(x=-0.6, y=0.4),
                        v3.Vertex(x=-0.6, y=-0.4),
                    ],
                )
            ],
            envelopes3d=[v3.Envelope3d(envelope3d_id="hull", format="DXF", url="http://x/y")],
        ),
        load_specification=v3.LoadSpecification(
            load_positions=["front"],
            load_sets=[
                v3.LoadSet(
                    set_name="pallet",
                    load_type="EPAL",
                    maximum_weight=500.0,
                    maximum_speed=1.0,
                    maximum_acceleration=0.3,
                    maximum_deceleration=0.5,
                    pick_time=2.0,
                )
            ],
        ),
        mobile_robot_configuration=v3.MobileRobotConfiguration(
            versions=[v3.VersionInfo(key="firmware", value="1.2")],
            network=v3.NetworkConfig(local_ip_address="10.0.0.5"),
            battery_charging=v3.BatteryCharging(critical_low_charging_level=10.0),
        ),
    )


def samples3() -> list[tuple[TopicKind, v3.Message]]:
    """At least one realistic 3.0 message of every one of the eight topics."""
    result: list[tuple[TopicKind, v3.Message]] = [
        (TopicKind.ORDER, make_order3()),
        (TopicKind.INSTANT_ACTIONS, make_instant_actions3()),
        (TopicKind.STATE, make_state3()),
        (TopicKind.STATE, make_state3_full()),
        (TopicKind.VISUALIZATION, make_visualization3()),
        (TopicKind.FACTSHEET, make_factsheet3()),
        (TopicKind.ZONE_SET, make_zone_set3()),
        (TopicKind.RESPONSES, make_responses3()),
    ]
    result += [(TopicKind.CONNECTION, make_connection3(s)) for s in v3.ConnectionState]
    return result


SAMPLES3 = samples3()
SAMPLE3_IDS = [f"{kind}-{i}" for i, (kind, _) in enumerate(SAMPLES3)]
