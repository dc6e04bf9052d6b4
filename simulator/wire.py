"""The message edge of a virtual vehicle: what it publishes and reads, in its version.

The vehicle logic is shared by all versions and works on the 2.x Structs. A 2.x vehicle
publishes them unchanged. A 3.0 vehicle converts them here with :mod:`vda5050.adapt`, plus
the 3.0 rules that only concern the message: the first node of a new order is not reported
in ``nodeStates`` (REFERENCE §3 A.3), instant actions go to ``instantActionStates``,
``visualization`` names the headerId of the latest state, CONNECTION_BROKEN is the last will;
its factsheet is built natively (:mod:`simulator.factsheet3`); a long ``instantActionStates``
adds INSTANT_ACTION_STATES_FULL (URGENT). Incoming 3.0 orders and
instant actions are converted to 2.x before the vehicle sees them (``initializePosition`` →
``initPosition``, edge ends from the neighbouring nodes, SINGLE kept as a string).
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import TYPE_CHECKING, TypeAlias

from simulator import messages
from simulator.execution import INSTANT_STATES_FULL
from simulator.factsheet3 import build_factsheet3
from vda5050 import (
    Connection,
    DecodeError,
    Factsheet,
    InstantActions,
    Order,
    Payload,
    State,
    Visualization,
    adapt,
    decode,
    v3,
)
from vda5050.enums import ConnectionState, ErrorType, TopicKind
from vda5050.headers import HEADER_ID_MODULUS

if TYPE_CHECKING:
    from simulator.vehicle import VirtualVehicle

__all__ = [
    "V3_ERROR_TYPES",
    "WireMessage",
    "connection",
    "decode_inbound",
    "factsheet",
    "state3",
    "states",
    "visualization",
]

#: What a vehicle publishes, 2.x or 3.0.
WireMessage: TypeAlias = (
    State
    | Visualization
    | Connection
    | Factsheet
    | v3.State
    | v3.Visualization
    | v3.Connection
    | v3.Factsheet
)

#: 3.0 name of each 2.x error type the simulator reports (REFERENCE §3 C.18); more specific
#: cases carry their own 3.0 type (:class:`simulator.orders.OrderRejected`).
V3_ERROR_TYPES: Mapping[str, str] = {
    ErrorType.VALIDATION_ERROR: v3.ErrorType.VALIDATION_FAILURE,
    ErrorType.ORDER_ERROR: v3.ErrorType.INVALID_ORDER_ACTION,
    ErrorType.ORDER_UPDATE_ERROR: v3.ErrorType.OUTDATED_ORDER_UPDATE,
    ErrorType.NO_ORDER_TO_CANCEL: v3.ErrorType.NO_ORDER_TO_CANCEL,
}


def _v3(vehicle: VirtualVehicle) -> bool:
    return vehicle.config.major >= 3


def states(vehicle: VirtualVehicle) -> list[State] | list[v3.State]:
    """The state messages to publish now (consumes state headerIds), shaped by the
    vehicle's misbehaviour: none while held back, two when duplicated or overtaken."""
    if not _v3(vehicle):
        return vehicle.build_states()
    return vehicle.saboteur.shape_states(state3(vehicle, messages.state_message(vehicle)))


def state3(vehicle: VirtualVehicle, state: State) -> v3.State:
    """``state`` (built by :func:`simulator.messages.state_message`) in 3.0 shape."""
    result = adapt.state_v2_to_v3(state, instant_action_ids=vehicle.actions.instant_ids)
    result.zone_sets = vehicle.map_store.zone_set_states() or None  # REFERENCE L.48
    result.zone_requests = vehicle.zone_requests.states()  # L.49
    pending = vehicle.pending
    if pending and pending[0].edge is None and result.node_states:
        result.node_states = result.node_states[1:]  # the first node is never a nodeState
    if len(result.instant_action_states) >= INSTANT_STATES_FULL:
        # REFERENCE §3 E.28: master control should send clearInstantActions.
        result.errors.append(
            v3.Error(
                error_type=v3.ErrorType.INSTANT_ACTION_STATES_FULL,
                error_description="instantActionStates is long; send clearInstantActions",
                error_level=v3.ErrorLevel.URGENT,
            )
        )
    return result


def visualization(vehicle: VirtualVehicle) -> Visualization | v3.Visualization:
    """The visualization message (consumes a visualization headerId)."""
    message = vehicle.build_visualization()
    if not _v3(vehicle):
        return message
    cfg = vehicle.config
    upcoming = vehicle.headers.peek(cfg.manufacturer, cfg.serial_number, TopicKind.STATE)
    latest = (upcoming - 1) % HEADER_ID_MODULUS if upcoming else 0
    return adapt.visualization_v2_to_v3(message, reference_state_header_id=latest)


def connection(vehicle: VirtualVehicle, state: ConnectionState) -> Connection | v3.Connection:
    """A connection message (ONLINE, OFFLINE or the last will); consumes a headerId."""
    message = vehicle.build_connection(state)
    return adapt.connection_v2_to_v3(message) if _v3(vehicle) else message


def factsheet(vehicle: VirtualVehicle) -> Factsheet | v3.Factsheet:
    """The factsheet (consumes a factsheet headerId)."""
    if not _v3(vehicle):
        return vehicle.build_factsheet()
    cfg = vehicle.config
    return build_factsheet3(
        **vehicle.headers.header(
            cfg.manufacturer, cfg.serial_number, TopicKind.FACTSHEET, cfg.version
        ),
        speed_max=cfg.wall_speed,
        state_interval=cfg.state_interval,
        visualization_hz=cfg.visualization_hz,
    )


def decode_inbound(kind: TopicKind, payload: Payload, version: str) -> Order | InstantActions:
    """Decode an ``order`` or ``instantActions`` payload of protocol ``version`` into the
    2.x Structs the vehicle works on.

    Raises:
        DecodeError: if the payload is not a valid message of that kind and version.
    """
    message = decode(kind, payload, version=version)
    if isinstance(message, v3.Order):
        return adapt.order_v3_to_v2(message)
    if isinstance(message, v3.InstantActions):
        return adapt.instant_actions_v3_to_v2(message)
    if isinstance(message, Order | InstantActions):
        return message
    raise DecodeError(kind, "the vehicle only reads order and instantActions")
