"""``factsheet`` from 3.0 to 2.x (REFERENCE §6 "factsheet").

Every renamed field maps onto its 2.x name (``mobileRobot*`` → ``agv*``, ``maximum*``/
``minimum*`` → ``max*``/``min*`` and ``*Max``/``*Min``, ``maximumStringLengths`` →
``maxStringLens``, ``maximumArrayLengths`` → ``maxArrayLens``, envelopes ``envelope2dId``/
``vertices`` → ``set``/``polygonPoints``, ``mobileRobotConfiguration`` → ``vehicleConfig``).
Extensible values are respelt where 2.x has them (DIFFERENTIAL → DIFF, OMNIDIRECTIONAL →
OMNI, THREE_WHEEL → THREEWHEEL, FREELY_NAVIGATING → AUTONOMOUS) and otherwise kept as 3.0
strings. Action types use their 2.x names (``initializePosition`` → ``initPosition``) so
master control checks instant actions in one vocabulary. The result describes what a 2.x
model can use, so it stays a valid 2.x factsheet for predefined values: blockingType SINGLE
and action scope ZONE are left out of the lists (a 2.x order cannot express them). Dropped
(no 2.x field): ``supportedZones``, ``pauseAllowed``, ``cancelAllowed``,
``maximumArrayLengths`` of ``zoneSet.zones``/``state.instantActionStates``/
``state.zoneActionStates``, ``batteryCharging``; 2.x ``enumLen`` stays unset.
"""

from __future__ import annotations

from typing import TypeVar

from vda5050 import v2, v3
from vda5050.adapt.common import action_type_v2, to_v2, to_v2_text
from vda5050.enums import (
    ActionScope,
    AgvClass,
    AgvKinematic,
    BlockingType,
    ValueDataType,
    WheelType,
)

__all__ = ["factsheet_v3_to_v2"]

_V2_SCOPES = frozenset(s.value for s in ActionScope)
_V2_BLOCKING = frozenset(b.value for b in BlockingType)


def factsheet_v3_to_v2(factsheet: v3.Factsheet) -> v2.Factsheet:
    """A 3.0 factsheet as the 2.x Factsheet master control reads capabilities from."""
    spec = factsheet.type_specification
    physical = factsheet.physical_parameters
    config = factsheet.mobile_robot_configuration
    return v2.Factsheet(
        header_id=factsheet.header_id,
        timestamp=factsheet.timestamp,
        version=factsheet.version,
        manufacturer=factsheet.manufacturer,
        serial_number=factsheet.serial_number,
        type_specification=v2.TypeSpecification(
            series_name=spec.series_name,
            series_description=spec.series_description,
            agv_kinematic=to_v2(AgvKinematic, spec.mobile_robot_kinematics),
            agv_class=to_v2(AgvClass, spec.mobile_robot_class),
            max_load_mass=spec.maximum_load_mass,
            localization_types=list(spec.localization_types),
            navigation_types=[to_v2_text(n) for n in spec.navigation_types],
        ),
        physical_parameters=v2.PhysicalParameters(
            speed_min=physical.minimum_speed,
            speed_max=physical.maximum_speed,
            angular_speed_min=physical.minimum_angular_speed,
            angular_speed_max=physical.maximum_angular_speed,
            acceleration_max=physical.maximum_acceleration,
            deceleration_max=physical.maximum_deceleration,
            height_min=physical.minimum_height,
            height_max=physical.maximum_height,
            width=physical.width,
            length=physical.length,
        ),
        protocol_limits=_limits_to_v2(factsheet.protocol_limits),
        protocol_features=v2.ProtocolFeatures(
            optional_parameters=list(factsheet.protocol_features.optional_parameters),
            agv_actions=[
                _action_to_v2(a) for a in factsheet.protocol_features.mobile_robot_actions
            ],
        ),
        agv_geometry=_geometry_to_v2(factsheet.mobile_robot_geometry),
        load_specification=v2.LoadSpecification(
            load_positions=_copy(factsheet.load_specification.load_positions),
            load_sets=(
                None
                if factsheet.load_specification.load_sets is None
                else [_load_set_to_v2(s) for s in factsheet.load_specification.load_sets]
            ),
        ),
        vehicle_config=(
            None
            if config is None
            else v2.VehicleConfig(versions=_copy(config.versions), network=config.network)
        ),
    )


T = TypeVar("T")


def _copy(items: list[T] | None) -> list[T] | None:
    return None if items is None else list(items)


def _limits_to_v2(limits: v3.ProtocolLimits) -> v2.ProtocolLimits:
    strings = limits.maximum_string_lengths
    arrays = limits.maximum_array_lengths
    timing = limits.timing
    return v2.ProtocolLimits(
        max_string_lens=v2.MaxStringLens(
            msg_len=strings.maximum_message_length,
            topic_serial_len=strings.maximum_topic_serial_length,
            topic_elem_len=strings.maximum_topic_element_length,
            id_len=strings.maximum_id_length,
            id_numerical_only=strings.id_numerical_only,
            load_id_len=strings.maximum_load_id_length,
        ),
        max_array_lens=v2.MaxArrayLens(
            order_nodes=arrays.order_nodes,
            order_edges=arrays.order_edges,
            node_actions=arrays.node_actions,
            edge_actions=arrays.edge_actions,
            actions_actions_parameters=arrays.actions_actions_parameters,
            instant_actions=arrays.instant_actions,
            trajectory_knot_vector=arrays.trajectory_knot_vector,
            trajectory_control_points=arrays.trajectory_control_points,
            state_node_states=arrays.state_node_states,
            state_edge_states=arrays.state_edge_states,
            state_loads=arrays.state_loads,
            state_action_states=arrays.state_action_states,
            state_errors=arrays.state_errors,
            state_information=arrays.state_information,
            error_error_references=arrays.error_error_references,
            information_info_references=arrays.information_info_references,
        ),
        timing=v2.Timing(
            min_order_interval=timing.minimum_order_interval,
            min_state_interval=timing.minimum_state_interval,
            default_state_interval=timing.default_state_interval,
            visualization_interval=timing.visualization_interval,
        ),
    )


def _action_to_v2(action: v3.MobileRobotAction) -> v2.AgvAction:
    return v2.AgvAction(
        action_type=action_type_v2(action.action_type),
        action_description=action.action_description,
        action_scopes=[ActionScope(s) for s in action.action_scopes if str(s) in _V2_SCOPES],
        action_parameters=(
            None
            if action.action_parameters is None
            else [
                v2.ActionParameterSpec(
                    key=p.key,
                    value_data_type=to_v2(ValueDataType, p.value_data_type),
                    description=p.description,
                    is_optional=p.is_optional,
                )
                for p in action.action_parameters
            ]
        ),
        result_description=action.action_result,
        blocking_types=(
            None
            if action.blocking_types is None
            else [BlockingType(b) for b in action.blocking_types if str(b) in _V2_BLOCKING]
        ),
    )


def _geometry_to_v2(geometry: v3.MobileRobotGeometry) -> v2.AgvGeometry:
    return v2.AgvGeometry(
        wheel_definitions=(
            None
            if geometry.wheel_definitions is None
            else [
                v2.WheelDefinition(
                    type=to_v2(WheelType, w.type),
                    is_active_driven=w.is_active_driven,
                    is_active_steered=w.is_active_steered,
                    position=w.position,
                    diameter=w.diameter,
                    width=w.width,
                    center_displacement=w.center_displacement,
                    constraints=w.constraints,
                )
                for w in geometry.wheel_definitions
            ]
        ),
        envelopes2d=(
            None
            if geometry.envelopes2d is None
            else [
                v2.Envelope2d(
                    set=e.envelope2d_id,
                    polygon_points=[v2.PolygonPoint(x=v.x, y=v.y) for v in e.vertices],
                    description=e.description,
                )
                for e in geometry.envelopes2d
            ]
        ),
        envelopes3d=(
            None
            if geometry.envelopes3d is None
            else [
                v2.Envelope3d(
                    set=e.envelope3d_id,
                    format=e.format,
                    data=e.data,
                    url=e.url,
                    description=e.description,
                )
                for e in geometry.envelopes3d
            ]
        ),
    )


def _load_set_to_v2(s: v3.LoadSet) -> v2.LoadSet:
    return v2.LoadSet(
        set_name=s.set_name,
        load_type=s.load_type,
        load_positions=_copy(s.load_positions),
        bounding_box_reference=s.bounding_box_reference,
        load_dimensions=s.load_dimensions,
        max_weight=s.maximum_weight,
        min_loadhandling_height=s.minimum_loadhandling_height,
        max_loadhandling_height=s.maximum_loadhandling_height,
        min_loadhandling_depth=s.minimum_loadhandling_depth,
        max_loadhandling_depth=s.maximum_loadhandling_depth,
        min_loadhandling_tilt=s.minimum_loadhandling_tilt,
        max_loadhandling_tilt=s.maximum_loadhandling_tilt,
        agv_speed_limit=s.maximum_speed,
        agv_acceleration_limit=s.maximum_acceleration,
        agv_deceleration_limit=s.maximum_deceleration,
        pick_time=s.pick_time,
        drop_time=s.drop_time,
        description=s.description,
    )
