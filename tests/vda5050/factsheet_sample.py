"""A realistic factsheet sample (split from samples.py for size)."""

from __future__ import annotations

from vda5050 import (
    ActionParameterSpec,
    ActionScope,
    AgvAction,
    AgvClass,
    AgvGeometry,
    AgvKinematic,
    BlockingType,
    BoundingBoxReference,
    Envelope2d,
    Envelope3d,
    Factsheet,
    LoadDimensions,
    LoadSet,
    LoadSpecification,
    LocalizationType,
    MaxArrayLens,
    MaxStringLens,
    NavigationType,
    NetworkConfig,
    OptionalParameter,
    PhysicalParameters,
    PolygonPoint,
    ProtocolFeatures,
    ProtocolLimits,
    Support,
    Timing,
    TypeSpecification,
    ValueDataType,
    VehicleConfig,
    VersionInfo,
    WheelDefinition,
    WheelPosition,
    WheelType,
)

from .support import header


def make_factsheet(version: str, *, upstream_compatible: bool = False) -> Factsheet:
    """A realistic factsheet of a differential-drive pallet carrier.

    ``upstream_compatible=True`` leaves out ``agvActions[].blockingTypes`` and
    ``envelopes3d[].description``, the only way to validate against the *unpatched*
    upstream schemas (see ``_patch_upstream_bugs``).
    """
    v21 = version == "2.1.0"

    def spec(key: str, kind: ValueDataType, optional: bool = False) -> ActionParameterSpec:
        return ActionParameterSpec(
            key=key, value_data_type=kind, description=f"{key} parameter", is_optional=optional
        )

    def agv_action(
        action_type: str,
        scopes: list[ActionScope],
        params: list[ActionParameterSpec] | None = None,
        blocking: list[BlockingType] | None = None,
    ) -> AgvAction:
        return AgvAction(
            action_type=action_type,
            action_description=f"{action_type} action",
            action_scopes=scopes,
            action_parameters=params,
            result_description="none",
            blocking_types=None if upstream_compatible else blocking,
        )

    instant = [ActionScope.INSTANT]
    return Factsheet(
        **header(version),
        type_specification=TypeSpecification(
            series_name="Carrier-1000",
            series_description="pallet carrier",
            agv_kinematic=AgvKinematic.DIFF,
            agv_class=AgvClass.CARRIER,
            max_load_mass=1000.0,
            localization_types=[LocalizationType.NATURAL, LocalizationType.REFLECTOR],
            navigation_types=[NavigationType.AUTONOMOUS],
        ),
        physical_parameters=PhysicalParameters(
            speed_min=0.01,
            speed_max=2.0,
            acceleration_max=0.8,
            deceleration_max=1.2,
            height_min=0.3,
            height_max=2.1,
            width=0.9,
            length=1.4,
        ),
        protocol_limits=ProtocolLimits(
            max_string_lens=MaxStringLens(
                msg_len=65536,
                topic_serial_len=32,
                topic_elem_len=32,
                id_len=64,
                id_numerical_only=False,
                enum_len=32,
                load_id_len=32,
            ),
            max_array_lens=MaxArrayLens(
                order_nodes=50,
                order_edges=49,
                node_actions=5,
                edge_actions=5,
                actions_actions_parameters=10,
                instant_actions=10,
                trajectory_knot_vector=20,
                trajectory_control_points=16,
                state_node_states=50,
                state_edge_states=49,
                state_loads=1,
                state_action_states=100,
                state_errors=20,
                state_information=20,
                error_error_references=5,
                information_info_references=5,
            ),
            timing=Timing(
                min_order_interval=1.0,
                min_state_interval=0.5,
                default_state_interval=30.0,
                visualization_interval=0.2,
            ),
        ),
        protocol_features=ProtocolFeatures(
            optional_parameters=[
                OptionalParameter(
                    parameter="order.nodes.nodePosition.theta", support=Support.REQUIRED
                ),
                OptionalParameter(
                    parameter="order.edges.trajectory",
                    support=Support.SUPPORTED,
                    description="NURBS up to degree 3",
                ),
            ],
            agv_actions=[
                agv_action("cancelOrder", instant, blocking=[BlockingType.NONE]),
                agv_action("startPause", instant, blocking=[BlockingType.NONE]),
                agv_action("stopPause", instant),
                agv_action("stateRequest", instant),
                agv_action("factsheetRequest", instant),
                agv_action(
                    "initPosition",
                    [ActionScope.INSTANT, ActionScope.NODE],
                    [
                        spec("x", ValueDataType.NUMBER),
                        spec("y", ValueDataType.NUMBER),
                        spec("theta", ValueDataType.NUMBER),
                        spec("mapId", ValueDataType.STRING),
                        spec("lastNodeId", ValueDataType.STRING),
                    ],
                ),
                agv_action(
                    "pick",
                    [ActionScope.NODE, ActionScope.EDGE],
                    [
                        spec("stationType", ValueDataType.STRING),
                        spec("loadType", ValueDataType.STRING),
                        spec("height", ValueDataType.FLOAT, optional=True),
                        spec("lhd", ValueDataType.ARRAY, optional=True),
                        spec("verify", ValueDataType.BOOL, optional=True),
                    ],
                    blocking=[BlockingType.SOFT, BlockingType.HARD],
                ),
            ],
        ),
        agv_geometry=AgvGeometry(
            wheel_definitions=[
                WheelDefinition(
                    type=WheelType.DRIVE,
                    is_active_driven=True,
                    is_active_steered=False,
                    position=WheelPosition(x=0.0, y=side * 0.35, theta=0.0),
                    diameter=0.2,
                    width=0.06,
                    center_displacement=0.0,
                    constraints="none",
                )
                for side in (1, -1)
            ]
            + [
                WheelDefinition(
                    type=WheelType.CASTER,
                    is_active_driven=False,
                    is_active_steered=False,
                    position=WheelPosition(x=0.55, y=0.0),
                    diameter=0.1,
                    width=0.04,
                )
            ],
            envelopes2d=[
                Envelope2d(
                    set="unloaded",
                    polygon_points=[
                        PolygonPoint(x=0.7, y=0.45),
                        PolygonPoint(x=-0.7, y=0.45),
                        PolygonPoint(x=-0.7, y=-0.45),
                        PolygonPoint(x=0.7, y=-0.45),
                    ],
                    description="footprint",
                )
            ],
            envelopes3d=[
                Envelope3d(
                    set="unloaded",
                    format="DXF",
                    url="https://example.com/carrier.dxf",
                    data={"units": "m"},
                    description=None if upstream_compatible else "outline",
                )
            ],
        ),
        load_specification=LoadSpecification(
            load_positions=["front"],
            load_sets=[
                LoadSet(
                    set_name="EPAL-default",
                    load_type="EPAL",
                    load_positions=["front"],
                    bounding_box_reference=BoundingBoxReference(x=0.0, y=0.0, z=0.1),
                    load_dimensions=LoadDimensions(length=1.2, width=0.8, height=1.5),
                    max_weight=1000.0,
                    min_loadhandling_height=0.0,
                    max_loadhandling_height=0.1,
                    min_loadhandling_depth=0.0,
                    max_loadhandling_depth=0.05,
                    min_loadhandling_tilt=0.0,
                    max_loadhandling_tilt=0.0,
                    agv_speed_limit=1.0,
                    agv_acceleration_limit=0.5,
                    agv_deceleration_limit=0.8,
                    pick_time=8.0,
                    drop_time=6.0,
                    description="Euro pallet",
                )
            ],
        ),
        localization_parameters=None if v21 else {"type": "NATURAL", "mapResolution": 0.05},
        vehicle_config=(
            VehicleConfig(
                versions=[VersionInfo(key="firmware", value="4.2.1")],
                network=NetworkConfig(
                    dns_servers=["10.0.0.2"],
                    local_ip_address="10.0.0.50",
                    ntp_servers=["10.0.0.3"],
                    netmask="255.255.255.0",
                    default_gateway="10.0.0.1",
                ),
            )
            if v21
            else None
        ),
    )
