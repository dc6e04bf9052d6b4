"""Small factories for correct messages, shared by master control and the simulator.

They fill in what is easy to get wrong by hand: UUID action ids, parameter lists,
protocol-format timestamps.
"""

from __future__ import annotations

import uuid
from collections.abc import Iterable, Mapping

from vda5050.enums import ActionType, BlockingType, ConnectionState
from vda5050.headers import now_timestamp
from vda5050.v2 import Action, ActionParameter, Connection, InstantActions, ParameterValue

__all__ = [
    "action_params",
    "cancel_order",
    "factsheet_request",
    "init_position",
    "instant_action",
    "make_action",
    "make_connection",
    "make_instant_actions",
    "start_pause",
    "state_request",
    "stop_pause",
]


def make_action(
    action_type: str,
    params: Mapping[str, ParameterValue] | None = None,
    blocking_type: BlockingType = BlockingType.NONE,
    *,
    action_id: str | None = None,
    description: str | None = None,
) -> Action:
    """Build an :class:`Action` with a fresh UUID4 ``actionId`` (the spec's suggestion).

    ``params`` becomes ``actionParameters`` in insertion order; ``None`` or an empty
    mapping omits the field.
    """
    parameters = (
        [ActionParameter(key=key, value=value) for key, value in params.items()] if params else None
    )
    return Action(
        action_type=str(action_type),
        action_id=action_id if action_id is not None else str(uuid.uuid4()),
        action_description=description,
        blocking_type=blocking_type,
        action_parameters=parameters,
    )


def action_params(action: Action) -> dict[str, ParameterValue]:
    """Return the parameters of ``action`` as a dict (later duplicates win)."""
    return {p.key: p.value for p in action.action_parameters or ()}


def make_instant_actions(
    actions: Iterable[Action],
    *,
    header_id: int,
    manufacturer: str,
    serial_number: str,
    version: str = "2.0.0",
    timestamp: str | None = None,
) -> InstantActions:
    """Wrap ``actions`` in an ``instantActions`` message (timestamp defaults to now)."""
    return InstantActions(
        header_id=header_id,
        timestamp=timestamp if timestamp is not None else now_timestamp(version),
        version=version,
        manufacturer=manufacturer,
        serial_number=serial_number,
        actions=list(actions),
    )


def instant_action(
    action_type: str,
    params: Mapping[str, ParameterValue] | None = None,
    blocking_type: BlockingType = BlockingType.NONE,
    *,
    header_id: int,
    manufacturer: str,
    serial_number: str,
    version: str = "2.0.0",
    timestamp: str | None = None,
) -> InstantActions:
    """Build an ``instantActions`` message holding a single new action."""
    return make_instant_actions(
        [make_action(action_type, params, blocking_type)],
        header_id=header_id,
        manufacturer=manufacturer,
        serial_number=serial_number,
        version=version,
        timestamp=timestamp,
    )


def make_connection(
    connection_state: ConnectionState,
    *,
    header_id: int,
    manufacturer: str,
    serial_number: str,
    version: str = "2.0.0",
    timestamp: str | None = None,
) -> Connection:
    """Build a ``connection`` message (ONLINE, OFFLINE or the CONNECTIONBROKEN last will)."""
    return Connection(
        header_id=header_id,
        timestamp=timestamp if timestamp is not None else now_timestamp(version),
        version=version,
        manufacturer=manufacturer,
        serial_number=serial_number,
        connection_state=connection_state,
    )


# Predefined instant actions (REFERENCE §4). They default to blockingType NONE: an
# instant action must never wait behind running order actions, and 3.0 makes NONE
# mandatory for instant actions, so this default stays valid on upgrade. Pass another
# blocking type only if the vehicle's factsheet lists it for that action.


def cancel_order(blocking_type: BlockingType = BlockingType.NONE) -> Action:
    """``cancelOrder``: stop the current order (then wait for FINISHED before a new one)."""
    return make_action(ActionType.CANCEL_ORDER, None, blocking_type)


def start_pause(blocking_type: BlockingType = BlockingType.NONE) -> Action:
    """``startPause``: pause driving and actions; the order is kept."""
    return make_action(ActionType.START_PAUSE, None, blocking_type)


def stop_pause(blocking_type: BlockingType = BlockingType.NONE) -> Action:
    """``stopPause``: resume after ``startPause``."""
    return make_action(ActionType.STOP_PAUSE, None, blocking_type)


def state_request(blocking_type: BlockingType = BlockingType.NONE) -> Action:
    """``stateRequest``: ask for an immediate ``state`` message."""
    return make_action(ActionType.STATE_REQUEST, None, blocking_type)


def factsheet_request(blocking_type: BlockingType = BlockingType.NONE) -> Action:
    """``factsheetRequest``: ask the vehicle to (re)publish its factsheet."""
    return make_action(ActionType.FACTSHEET_REQUEST, None, blocking_type)


def init_position(
    *,
    x: float,
    y: float,
    theta: float,
    map_id: str,
    last_node_id: str,
    blocking_type: BlockingType = BlockingType.NONE,
) -> Action:
    """``initPosition``: set the vehicle pose (metres, radians) on ``map_id``."""
    return make_action(
        ActionType.INIT_POSITION,
        {"x": x, "y": y, "theta": theta, "mapId": map_id, "lastNodeId": last_node_id},
        blocking_type,
    )
