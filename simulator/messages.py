"""Builders of the messages a virtual vehicle publishes (state, visualization, connection,
factsheet). Each builder consumes one headerId of its topic: headerIds count *sent*
messages per topic (REFERENCE §2), and a built message is always sent.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from simulator.factsheet import build_factsheet
from vda5050 import (
    ActionState,
    AgvPosition,
    BatteryState,
    Connection,
    EdgeState,
    Error,
    Factsheet,
    NodeState,
    SafetyState,
    State,
    Velocity,
    Visualization,
)
from vda5050.enums import (
    ConnectionState,
    ErrorLevel,
    EStop,
    TopicKind,
)
from vda5050.headers import HeaderFields
from vda5050.versions import major_of

if TYPE_CHECKING:
    from simulator.vehicle import VirtualVehicle


def _header(vehicle: VirtualVehicle, kind: TopicKind) -> HeaderFields:
    """Header of the next message on topic ``kind`` (next headerId, timestamp per version)."""
    cfg = vehicle.config
    return vehicle.headers.header(cfg.manufacturer, cfg.serial_number, kind, cfg.version)


def is_v21(version: str) -> bool:
    """True for protocol 2.1.x and later (3.x), which have ``state.maps`` and the vehicle
    configuration in the factsheet."""
    return version.startswith("2.1") or major_of(version) >= 3


def agv_position(vehicle: VirtualVehicle) -> AgvPosition:
    """Current pose as reported in state and visualization."""
    return AgvPosition(
        x=round(vehicle.x, 4),
        y=round(vehicle.y, 4),
        theta=round(vehicle.theta, 4),
        map_id=vehicle.map_id,
        position_initialized=vehicle.position_initialized,
        localization_score=1.0,
    )


def velocity(vehicle: VirtualVehicle) -> Velocity:
    """Velocity in vehicle coordinates (straight-line driving: vx only)."""
    return Velocity(vx=round(vehicle.speed_now, 4), vy=0.0, omega=0.0)


def _errors(vehicle: VirtualVehicle) -> list[Error]:
    battery = (
        [
            Error(
                error_type="batteryEmpty",
                error_description="battery is empty; charge before driving",
                error_level=ErrorLevel.FATAL,
            )
        ]
        if vehicle.battery <= 0.0
        else []
    )
    return [*vehicle.order_errors, *vehicle.action_errors, *vehicle.injected_errors, *battery]


def state_message(vehicle: VirtualVehicle) -> State:
    """Assemble the state message of ``vehicle``."""
    cfg = vehicle.config
    pending = vehicle.pending
    # Standing at the end of the base with a horizon left: ask master control to extend.
    waiting_for_base = (
        bool(pending) and not pending[0].released and not vehicle.driving and not vehicle.cancelled
    )
    return State(
        **_header(vehicle, TopicKind.STATE),
        maps=vehicle.map_store.states() if is_v21(cfg.version) else None,
        order_id=vehicle.order_id,
        order_update_id=vehicle.order_update_id,
        last_node_id=vehicle.last_node_id,
        last_node_sequence_id=vehicle.last_node_sequence_id,
        driving=vehicle.driving,
        paused=vehicle.paused,
        new_base_request=waiting_for_base,
        distance_since_last_node=round(vehicle.distance_since_last_node, 4),
        operating_mode=vehicle.operating_mode,
        node_states=[
            NodeState(
                node_id=s.node.node_id,
                sequence_id=s.node.sequence_id,
                node_description=s.node.node_description,
                released=s.node.released,
                node_position=s.node.node_position,
            )
            for s in pending
        ],
        edge_states=[
            EdgeState(
                edge_id=s.edge.edge_id,
                sequence_id=s.edge.sequence_id,
                edge_description=s.edge.edge_description,
                released=s.edge.released,
            )
            for s in pending
            if s.edge is not None
        ],
        agv_position=agv_position(vehicle),
        velocity=velocity(vehicle),
        loads=list(vehicle.loads),
        action_states=[
            ActionState(
                action_id=run.action_id,
                action_type=run.action.action_type,
                action_description=run.action.action_description,
                action_status=run.status,
                result_description=run.result,
            )
            for run in vehicle.actions.reported()
        ],
        battery_state=BatteryState(
            battery_charge=round(vehicle.battery, 2),
            charging=vehicle.charging,
            reach=(
                round(vehicle.battery / cfg.battery_drain_per_metre, 1)
                if cfg.battery_drain_per_metre > 0
                else None
            ),
        ),
        errors=_errors(vehicle),
        safety_state=SafetyState(e_stop=EStop.NONE, field_violation=False),
    )


def visualization_message(vehicle: VirtualVehicle) -> Visualization:
    """Assemble a visualization message (pose and velocity only)."""
    return Visualization(
        **_header(vehicle, TopicKind.VISUALIZATION),
        agv_position=agv_position(vehicle),
        velocity=velocity(vehicle),
    )


def connection_message(vehicle: VirtualVehicle, state: ConnectionState) -> Connection:
    """Assemble a connection message with ``state``."""
    return Connection(
        **_header(vehicle, TopicKind.CONNECTION),
        connection_state=state,
    )


def factsheet_message(vehicle: VirtualVehicle) -> Factsheet:
    """Assemble the factsheet describing what the simulated vehicle supports."""
    cfg = vehicle.config
    return build_factsheet(
        **_header(vehicle, TopicKind.FACTSHEET),
        speed_max=cfg.wall_speed,
        state_interval=cfg.state_interval,
        visualization_hz=cfg.visualization_hz,
        with_vehicle_config=is_v21(cfg.version),
    )
