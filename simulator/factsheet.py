"""The factsheet every simulated vehicle publishes (retained) on connect and on request."""

from __future__ import annotations

from simulator.actions import CATALOGUE, catalogue
from vda5050 import (
    ActionParameterSpec,
    AgvAction,
    AgvGeometry,
    Envelope2d,
    Factsheet,
    LoadDimensions,
    LoadSet,
    LoadSpecification,
    MaxArrayLens,
    MaxStringLens,
    OptionalParameter,
    PhysicalParameters,
    PolygonPoint,
    ProtocolFeatures,
    ProtocolLimits,
    Timing,
    TypeSpecification,
    VehicleConfig,
    VersionInfo,
)
from vda5050.enums import (
    AgvClass,
    AgvKinematic,
    BlockingType,
    LocalizationType,
    NavigationType,
    Support,
)

#: Vehicle footprint in metres; the envelope is the rectangle around the kinematic centre.
LENGTH = 1.2
WIDTH = 0.8
HEIGHT = 0.4
MAX_LOAD_KG = 500.0
SIMULATOR_VERSION = "0.1.0"

# Order fields the simulator reads; everything else in an order is ignored, so it must not
# be advertised (REFERENCE §3 A.6: the master only sends supported optional parameters).
_OPTIONAL_PARAMETERS = (
    ("order.nodes.nodePosition", "Coordinates to drive to; falls back to the layout."),
    ("order.nodes.nodePosition.allowedDeviationXY", "Enlarges the start-node reach."),
    ("order.nodes.nodePosition.theta", "Heading taken on arrival."),
    ("order.edges.maxSpeed", "Caps the driving speed on that edge."),
)


def _agv_actions() -> list[AgvAction]:
    return [
        AgvAction(
            action_type=spec.action_type,
            action_description=spec.description,
            action_scopes=list(spec.scopes),
            action_parameters=[
                ActionParameterSpec(
                    key=p.key,
                    value_data_type=p.data_type,
                    description=p.description,
                    is_optional=p.optional,
                )
                for p in spec.parameters
            ]
            or None,
            blocking_types=[BlockingType(b) for b in spec.blocking_types],
        )
        for spec in catalogue(2)
    ]


def build_factsheet(
    *,
    header_id: int,
    timestamp: str,
    version: str,
    manufacturer: str,
    serial_number: str,
    speed_max: float,
    state_interval: float,
    visualization_hz: float,
    with_vehicle_config: bool,
) -> Factsheet:
    """Describe the simulated carrier; ``vehicleConfig`` exists only in 2.1."""
    half_l, half_w = LENGTH / 2, WIDTH / 2
    return Factsheet(
        header_id=header_id,
        timestamp=timestamp,
        version=version,
        manufacturer=manufacturer,
        serial_number=serial_number,
        type_specification=TypeSpecification(
            series_name="SimCarrier",
            series_description="Virtual differential-drive carrier (VDA 5050 simulator)",
            agv_kinematic=AgvKinematic.DIFF,
            agv_class=AgvClass.CARRIER,
            max_load_mass=MAX_LOAD_KG,
            localization_types=[LocalizationType.NATURAL],
            navigation_types=[NavigationType.AUTONOMOUS],
        ),
        physical_parameters=PhysicalParameters(
            speed_min=0.0,
            speed_max=speed_max,
            acceleration_max=0.5,
            deceleration_max=0.5,
            height_min=HEIGHT,
            height_max=HEIGHT,
            width=WIDTH,
            length=LENGTH,
        ),
        protocol_limits=ProtocolLimits(
            max_string_lens=MaxStringLens(msg_len=1_048_576, id_len=128, id_numerical_only=False),
            max_array_lens=MaxArrayLens(
                order_nodes=1000, order_edges=999, node_actions=20, instant_actions=20
            ),
            timing=Timing(
                min_order_interval=0.0,
                min_state_interval=0.0,
                default_state_interval=state_interval,
                visualization_interval=1.0 / visualization_hz if visualization_hz > 0 else None,
            ),
        ),
        protocol_features=ProtocolFeatures(
            optional_parameters=[
                OptionalParameter(parameter=name, support=Support.SUPPORTED, description=text)
                for name, text in _OPTIONAL_PARAMETERS
            ],
            agv_actions=_agv_actions(),
        ),
        agv_geometry=AgvGeometry(
            envelopes2d=[
                Envelope2d(
                    set="default",
                    polygon_points=[
                        PolygonPoint(x=half_l, y=half_w),
                        PolygonPoint(x=-half_l, y=half_w),
                        PolygonPoint(x=-half_l, y=-half_w),
                        PolygonPoint(x=half_l, y=-half_w),
                    ],
                    description="Rectangular footprint around the kinematic centre",
                )
            ]
        ),
        load_specification=LoadSpecification(
            load_positions=["default"],
            load_sets=[
                LoadSet(
                    set_name="default",
                    load_type="EPAL",
                    load_positions=["default"],
                    load_dimensions=LoadDimensions(length=1.2, width=0.8, height=1.0),
                    max_weight=MAX_LOAD_KG,
                    pick_time=CATALOGUE["pick"].duration,
                    drop_time=CATALOGUE["drop"].duration,
                )
            ],
        ),
        vehicle_config=(
            VehicleConfig(versions=[VersionInfo(key="simulator", value=SIMULATOR_VERSION)])
            if with_vehicle_config
            else None
        ),
    )
