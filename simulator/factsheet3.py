"""The 3.0.0 factsheet of a simulated vehicle (3.0 names, built from the same catalogue).

Same vehicle as :mod:`simulator.factsheet`, described in 3.0 terms: ``mobileRobot*``,
``maximum*``/``minimum*``, ``initializePosition``, 3.0-only actions, SINGLE where offered,
``pauseAllowed``/``cancelAllowed`` (startPause freezes running actions; cancelOrder lets a
running action finish, so none is cancellable), instant actions with blockingType NONE.
"""

from __future__ import annotations

from simulator.actions import CATALOGUE, ActionSpec, catalogue
from simulator.execution import INSTANT_STATES_MAX
from simulator.factsheet import HEIGHT, LENGTH, MAX_LOAD_KG, SIMULATOR_VERSION, WIDTH
from vda5050 import v3
from vda5050.adapt import action_type_v3
from vda5050.enums import ActionScope, LocalizationType, Support

__all__ = ["build_factsheet3"]

# Order fields the simulator reads, in 3.0 names (REFERENCE §3 A.6).
_OPTIONAL_PARAMETERS = (
    ("order.nodes.nodePosition", "Coordinates to drive to; falls back to the layout."),
    (
        "order.nodes.nodePosition.allowedDeviationXY",
        "Enlarges the start-node reach (by the smaller semi-axis).",
    ),
    ("order.nodes.nodePosition.theta", "Heading taken on arrival."),
    ("order.edges.maximumSpeed", "Caps the driving speed on that edge."),
)
# 3.0 cancelOrder may name the order to cancel (REFERENCE §4).
_EXTRA_PARAMETERS = {
    "cancelOrder": [
        v3.ActionParameterSpec(
            key="orderId",
            value_data_type=v3.ValueDataType.STRING,
            description="Cancel only if this is the active order.",
            is_optional=True,
        )
    ]
}


def _blocking_types(spec: ActionSpec) -> list[v3.BlockingType]:
    """The node blocking types, plus NONE where the action is also instant (3.0: always NONE)."""
    allowed = set()
    if ActionScope.NODE in spec.scopes:
        allowed = {v3.BlockingType(b) for b in spec.blocking_types}
    if ActionScope.INSTANT in spec.scopes:
        allowed.add(v3.BlockingType.NONE)
    return [b for b in v3.BlockingType if b in allowed]


def _actions() -> list[v3.MobileRobotAction]:
    return [
        v3.MobileRobotAction(
            action_type=action_type_v3(spec.action_type),
            action_description=spec.description,
            action_scopes=[v3.ActionScope(scope) for scope in spec.scopes],
            action_parameters=[
                v3.ActionParameterSpec(
                    key=p.key,
                    value_data_type=v3.ValueDataType(p.data_type),
                    description=p.description,
                    is_optional=p.optional,
                )
                for p in spec.parameters
            ]
            + _EXTRA_PARAMETERS.get(spec.action_type, [])
            or None,
            blocking_types=_blocking_types(spec),
            pause_allowed=spec.duration > 0,
            cancel_allowed=False,
        )
        for spec in catalogue(3)
    ]


def build_factsheet3(
    *,
    header_id: int,
    timestamp: str,
    version: str,
    manufacturer: str,
    serial_number: str,
    speed_max: float,
    state_interval: float,
    visualization_hz: float,
) -> v3.Factsheet:
    """Describe the simulated carrier in 3.0 terms."""
    half_l, half_w = LENGTH / 2, WIDTH / 2
    return v3.Factsheet(
        header_id=header_id,
        timestamp=timestamp,
        version=version,
        manufacturer=manufacturer,
        serial_number=serial_number,
        type_specification=v3.TypeSpecification(
            series_name="SimCarrier",
            series_description="Virtual differential-drive carrier (VDA 5050 simulator)",
            mobile_robot_kinematics=v3.MobileRobotKinematics.DIFFERENTIAL,
            mobile_robot_class=v3.MobileRobotClass.CARRIER,
            maximum_load_mass=MAX_LOAD_KG,
            localization_types=[LocalizationType.NATURAL],
            navigation_types=[v3.NavigationType.FREELY_NAVIGATING],
            supported_zones=[v3.ZoneType.BLOCKED, v3.ZoneType.SPEED_LIMIT, v3.ZoneType.RELEASE],
        ),
        physical_parameters=v3.PhysicalParameters(
            minimum_speed=0.0,
            maximum_speed=speed_max,
            maximum_acceleration=0.5,
            maximum_deceleration=0.5,
            minimum_height=HEIGHT,
            maximum_height=HEIGHT,
            width=WIDTH,
            length=LENGTH,
        ),
        protocol_limits=v3.ProtocolLimits(
            maximum_string_lengths=v3.MaximumStringLengths(
                maximum_message_length=1_048_576, maximum_id_length=128, id_numerical_only=False
            ),
            maximum_array_lengths=v3.MaximumArrayLengths(
                order_nodes=1000,
                order_edges=999,
                node_actions=20,
                instant_actions=20,
                state_instant_action_states=INSTANT_STATES_MAX,
            ),
            timing=v3.Timing(
                minimum_order_interval=0.0,
                minimum_state_interval=0.0,
                default_state_interval=state_interval,
                visualization_interval=1.0 / visualization_hz if visualization_hz > 0 else None,
            ),
        ),
        protocol_features=v3.ProtocolFeatures(
            optional_parameters=[
                v3.OptionalParameter(parameter=name, support=Support.SUPPORTED, description=text)
                for name, text in _OPTIONAL_PARAMETERS
            ],
            mobile_robot_actions=_actions(),
        ),
        mobile_robot_geometry=v3.MobileRobotGeometry(
            envelopes2d=[
                v3.Envelope2d(
                    envelope2d_id="default",
                    vertices=[
                        v3.Vertex(x=half_l, y=half_w),
                        v3.Vertex(x=-half_l, y=half_w),
                        v3.Vertex(x=-half_l, y=-half_w),
                        v3.Vertex(x=half_l, y=-half_w),
                    ],
                    description="Rectangular footprint around the kinematic centre",
                )
            ]
        ),
        load_specification=v3.LoadSpecification(
            load_positions=["default"],
            load_sets=[
                v3.LoadSet(
                    set_name="default",
                    load_type="EPAL",
                    load_positions=["default"],
                    load_dimensions=v3.LoadDimensions(length=1.2, width=0.8, height=1.0),
                    maximum_weight=MAX_LOAD_KG,
                    pick_time=CATALOGUE["pick"].duration,
                    drop_time=CATALOGUE["drop"].duration,
                )
            ],
        ),
        mobile_robot_configuration=v3.MobileRobotConfiguration(
            versions=[v3.VersionInfo(key="simulator", value=SIMULATOR_VERSION)]
        ),
    )
