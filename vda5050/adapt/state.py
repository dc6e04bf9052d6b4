"""``state`` between 3.0 and 2.x (REFERENCE §6).

3.0 → 2.x (master control keeps one 2.x model): ``mobileRobotPosition`` → ``agvPosition``
(``localized`` → ``positionInitialized``), ``powerSupply`` → ``batteryState``
(``batteryCurrent`` dropped), ``actionStates`` + ``instantActionStates`` → ``actionStates``
(order actions first; ``zoneActionStates`` are left out: they are neither order nor instant
actions and must not keep the vehicle from being idle), ``activeEmergencyStop`` → ``eStop``,
``zoneSets`` → ``zoneSetId`` (the ENABLED set of the current map, else the first ENABLED
one), ``*Descriptor`` → ``*Description``, ``initializePosition`` → ``initPosition``,
``actionResult`` → ``resultDescription``. actionStatus RETRIABLE → PAUSED, marked in
``resultDescription`` (not terminal: the order is not done; see
:func:`~vda5050.adapt.common.is_retriable`). Operating mode TEACH_IN → TEACHIN; STARTUP and
INTERVENED stay 3.0 strings, which master control treats as "not automatic". Error
levels: URGENT → WARNING (the robot continues) and CRITICAL → FATAL: master control then
fails and cancels the order, which is right for CRITICAL (REFERENCE §3 G.36), but it also
treats the vehicle as unavailable while the error lasts although a CRITICAL robot may take
a new order; :func:`~vda5050.adapt.common.error_level_v3` tells the two apart. Dropped:
``zoneRequests``, ``edgeRequests``, ``plannedPath``, ``intermediatePath``, translations.
A 3.0 ``edgeStates[].trajectory`` without ``knotVector`` gets the clamped uniform one.

2.x → 3.0 (the vehicle side, e.g. the simulator speaking 3.0) is the inverse; it needs the
ids of the instant actions to split ``actionStates``. 2.x ``eStop`` AUTOACK has no 3.0 value
and becomes NONE with ``fieldViolation`` true (a protective field or bumper).
"""

from __future__ import annotations

from collections.abc import Collection

from vda5050 import v2, v3
from vda5050.adapt.common import (
    ERROR_LEVEL_KEY,
    action_type_v2,
    action_type_v3,
    error_level_v3,
    is_retriable,
    retriable_result,
    to_v2,
    to_v3,
    unmark_retriable,
)
from vda5050.adapt.messages import position_to_v2, position_to_v3
from vda5050.adapt.order import trajectory_to_v2, trajectory_to_v3
from vda5050.enums import ActionStatus, ErrorLevel, EStop, OperatingMode

__all__ = ["state_v2_to_v3", "state_v3_to_v2"]


def state_v3_to_v2(state: v3.State) -> v2.State:
    """A 3.0 ``state`` as the 2.x State master control works with (see module docstring)."""
    return v2.State(
        header_id=state.header_id,
        timestamp=state.timestamp,
        version=state.version,
        manufacturer=state.manufacturer,
        serial_number=state.serial_number,
        maps=None if state.maps is None else [_map_to_v2(m) for m in state.maps],
        order_id=state.order_id,
        order_update_id=state.order_update_id,
        zone_set_id=_active_zone_set(state),
        last_node_id=state.last_node_id,
        last_node_sequence_id=state.last_node_sequence_id,
        driving=state.driving,
        paused=state.paused,
        new_base_request=state.new_base_request,
        distance_since_last_node=state.distance_since_last_node,
        operating_mode=to_v2(OperatingMode, state.operating_mode),
        node_states=[_node_state_to_v2(n) for n in state.node_states],
        edge_states=[
            v2.EdgeState(
                edge_id=e.edge_id,
                sequence_id=e.sequence_id,
                edge_description=e.edge_descriptor,
                released=e.released,
                trajectory=trajectory_to_v2(e.trajectory),
            )
            for e in state.edge_states
        ],
        agv_position=position_to_v2(state.mobile_robot_position),
        velocity=state.velocity,
        loads=None if state.loads is None else list(state.loads),
        action_states=[
            _action_state_to_v2(a) for a in (*state.action_states, *state.instant_action_states)
        ],
        battery_state=v2.BatteryState(
            battery_charge=state.power_supply.state_of_charge,
            battery_voltage=state.power_supply.battery_voltage,
            battery_health=state.power_supply.battery_health,
            charging=state.power_supply.charging,
            reach=state.power_supply.range,
        ),
        errors=[_error_to_v2(e) for e in state.errors],
        information=None
        if state.information is None
        else [_info_to_v2(i) for i in state.information],
        safety_state=v2.SafetyState(
            e_stop=to_v2(EStop, state.safety_state.active_emergency_stop),
            field_violation=state.safety_state.field_violation,
        ),
    )


def state_v2_to_v3(state: v2.State, *, instant_action_ids: Collection[str] = ()) -> v3.State:
    """A 2.x State in 3.0 shape; ``actionStates`` listed in ``instant_action_ids`` go to
    ``instantActionStates``, the others stay order ``actionStates``."""
    e_stop = state.safety_state.e_stop
    position = state.agv_position
    zone_sets = None
    if state.zone_set_id is not None and position is not None:
        zone_sets = [
            v3.ZoneSetState(
                zone_set_id=state.zone_set_id,
                map_id=position.map_id,
                zone_set_status=v3.ZoneSetStatus.ENABLED,
            )
        ]
    battery = state.battery_state
    return v3.State(
        header_id=state.header_id,
        timestamp=state.timestamp,
        version=state.version,
        manufacturer=state.manufacturer,
        serial_number=state.serial_number,
        maps=None if state.maps is None else [_map_to_v3(m) for m in state.maps],
        zone_sets=zone_sets,
        order_id=state.order_id,
        order_update_id=state.order_update_id,
        last_node_id=state.last_node_id,
        last_node_sequence_id=state.last_node_sequence_id,
        node_states=[_node_state_to_v3(n) for n in state.node_states],
        edge_states=[
            v3.EdgeState(
                edge_id=e.edge_id,
                sequence_id=e.sequence_id,
                edge_descriptor=e.edge_description,
                released=e.released,
                trajectory=trajectory_to_v3(e.trajectory),
            )
            for e in state.edge_states
        ],
        mobile_robot_position=position_to_v3(position),
        velocity=state.velocity,
        loads=None if state.loads is None else list(state.loads),
        driving=state.driving,
        paused=state.paused,
        new_base_request=state.new_base_request,
        distance_since_last_node=state.distance_since_last_node,
        action_states=[
            _action_state_to_v3(a)
            for a in state.action_states
            if a.action_id not in instant_action_ids
        ],
        instant_action_states=[
            _action_state_to_v3(a) for a in state.action_states if a.action_id in instant_action_ids
        ],
        power_supply=v3.PowerSupply(
            state_of_charge=battery.battery_charge,
            battery_voltage=battery.battery_voltage,
            battery_health=battery.battery_health,
            charging=battery.charging,
            range=battery.reach,
        ),
        operating_mode=to_v3(v3.OperatingMode, state.operating_mode),
        errors=[_error_to_v3(e) for e in state.errors],
        information=None
        if state.information is None
        else [_info_to_v3(i) for i in state.information],
        safety_state=v3.SafetyState(
            active_emergency_stop=(
                v3.ActiveEmergencyStop.NONE
                if e_stop == EStop.AUTOACK
                else to_v3(v3.ActiveEmergencyStop, e_stop)
            ),
            field_violation=state.safety_state.field_violation or e_stop == EStop.AUTOACK,
        ),
    )


# --- parts ---------------------------------------------------------------------------------


def _active_zone_set(state: v3.State) -> str | None:
    enabled = [z for z in state.zone_sets or () if z.zone_set_status == v3.ZoneSetStatus.ENABLED]
    position = state.mobile_robot_position
    here = [z for z in enabled if position is not None and z.map_id == position.map_id]
    chosen = here or enabled
    return chosen[0].zone_set_id if chosen else None


def _map_to_v2(m: v3.MapState) -> v2.MapState:
    return v2.MapState(
        map_id=m.map_id,
        map_version=m.map_version,
        map_description=m.map_descriptor,
        map_status=m.map_status,
    )


def _map_to_v3(m: v2.MapState) -> v3.MapState:
    return v3.MapState(
        map_id=m.map_id,
        map_version=m.map_version,
        map_descriptor=m.map_description,
        map_status=m.map_status,
    )


def _node_state_to_v2(n: v3.NodeState) -> v2.NodeState:
    pos = n.node_position
    return v2.NodeState(
        node_id=n.node_id,
        sequence_id=n.sequence_id,
        node_description=n.node_descriptor,
        released=n.released,
        node_position=(
            None
            if pos is None
            else v2.NodePosition(x=pos.x, y=pos.y, theta=pos.theta, map_id=pos.map_id)
        ),
    )


def _node_state_to_v3(n: v2.NodeState) -> v3.NodeState:
    pos = n.node_position
    return v3.NodeState(
        node_id=n.node_id,
        sequence_id=n.sequence_id,
        node_descriptor=n.node_description,
        released=n.released,
        node_position=(
            None
            if pos is None
            else v3.NodeStatePosition(x=pos.x, y=pos.y, theta=pos.theta, map_id=pos.map_id)
        ),
    )


def _action_state_to_v2(a: v3.ActionState) -> v2.ActionState:
    retriable = a.action_status == v3.ActionStatus.RETRIABLE
    return v2.ActionState(
        action_id=a.action_id,
        action_type=None if a.action_type is None else action_type_v2(a.action_type),
        action_description=a.action_descriptor,
        action_status=ActionStatus.PAUSED if retriable else ActionStatus(a.action_status),
        result_description=retriable_result(a.action_result) if retriable else a.action_result,
    )


def _action_state_to_v3(a: v2.ActionState) -> v3.ActionState:
    retriable = is_retriable(a)
    return v3.ActionState(
        action_id=a.action_id,
        action_type=None if a.action_type is None else action_type_v3(a.action_type),
        action_descriptor=a.action_description,
        action_status=v3.ActionStatus.RETRIABLE
        if retriable
        else to_v3(v3.ActionStatus, a.action_status),
        action_result=unmark_retriable(a.result_description) if retriable else a.result_description,
    )


def _error_to_v2(e: v3.Error) -> v2.Error:
    refs = list(e.error_references or ())
    if e.error_level in (v3.ErrorLevel.URGENT, v3.ErrorLevel.CRITICAL):
        refs.append(
            v2.ErrorReference(reference_key=ERROR_LEVEL_KEY, reference_value=str(e.error_level))
        )
    severe = e.error_level in (v3.ErrorLevel.CRITICAL, v3.ErrorLevel.FATAL)
    return v2.Error(
        error_type=e.error_type,
        error_references=refs or None,
        error_description=e.error_description,
        error_hint=e.error_hint,
        error_level=ErrorLevel.FATAL if severe else ErrorLevel.WARNING,
    )


def _error_to_v3(e: v2.Error) -> v3.Error:
    level = error_level_v3(e)
    refs = [
        r
        for r in e.error_references or ()
        if not (r.reference_key == ERROR_LEVEL_KEY and r.reference_value == level)
    ]
    return v3.Error(
        error_type=e.error_type,
        error_references=refs or None,
        error_description=e.error_description,
        error_hint=e.error_hint,
        error_level=level,
    )


def _info_to_v2(i: v3.Information) -> v2.Information:
    return v2.Information(
        info_type=i.info_type,
        info_references=None if i.info_references is None else list(i.info_references),
        info_description=i.info_descriptor,
        info_level=i.info_level,
    )


def _info_to_v3(i: v2.Information) -> v3.Information:
    return v3.Information(
        info_type=i.info_type,
        info_references=None if i.info_references is None else list(i.info_references),
        info_descriptor=i.info_description,
        info_level=i.info_level,
    )
