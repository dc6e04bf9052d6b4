"""REFERENCE E.23: an instant action must not conflict with the running order or the vehicle.

The factsheet says what a vehicle can do (`control.capabilities`); this module says whether it
may be done *now*. Every predefined instant action of 2.0, 2.1 and 3.0 has a rule here; an
action type we do not know is judged by the factsheet alone. The reason is shown to the
operator and recorded on the VehicleCommand.
"""

from collections.abc import Mapping

import vda5050
from vda5050.adapt import is_retriable

# Actions that move the vehicle's idea of where it is, or make it stand still for a long time:
# never while it drives an order (REFERENCE §4: initPosition for relocation, charging only
# when no order is running, hibernation and shutdown only when idle).
_IDLE_ONLY = {
    "initPosition": "initPosition relocates the vehicle",
    "initializePosition": "initializePosition relocates the vehicle",
    "startCharging": "startCharging keeps the vehicle at the charger",
    "startHibernation": "startHibernation clears the vehicle's order",
    "shutdown": "shutdown needs an idle vehicle",
}
# Load handling and the like belong to nodes and edges of an order (scope N/E), never next to
# one as an instant action.
_ORDER_ACTIONS = frozenset({"pick", "drop", "detectObject", "finePositioning", "waitForTrigger"})
# Map changes under a vehicle that drives on that map.
_MAP_ACTIONS = frozenset({"enableMap", "deleteMap"})


def refuse_conflict(
    action_type: str,
    parameters: Mapping[str, object],
    state: vda5050.State | None,
    *,
    controlled_order: str | None = None,
) -> str | None:
    """Why `action_type` must not be sent now, or None if it does not conflict.

    `controlled_order` is the orderId `control` is driving on the vehicle, if any.
    """
    order_id = controlled_order or (state.order_id if state is not None else "") or ""
    busy = state is not None and bool(state.node_states or state.edge_states)
    active = busy or controlled_order is not None
    if action_type in _IDLE_ONLY:
        if active:
            return f"{_IDLE_ONLY[action_type]}; not while order {order_id} is running"
        if state is not None and state.driving:
            return f"{_IDLE_ONLY[action_type]}; not while the vehicle is driving"
        return None
    if action_type in _ORDER_ACTIONS and active:
        return f"{action_type} would run beside order {order_id}; send it as part of an order"
    if action_type in _MAP_ACTIONS and active:
        return _map_conflict(action_type, parameters, state, order_id)
    if action_type == "cancelOrder" and controlled_order is not None:
        return f"order {controlled_order} is driven by control: cancel its transport order"
    if action_type in {"retry", "skipRetry"}:
        return _retry_conflict(action_type, parameters, state)
    if action_type == "trigger":
        return "no waitForTrigger action is waiting: control never sends one"
    return None


def _map_conflict(
    action_type: str, parameters: Mapping[str, object], state: vda5050.State | None, order_id: str
) -> str | None:
    position = state.agv_position if state is not None else None
    map_id = parameters.get("mapId")
    if position is None or map_id == position.map_id:
        return f"{action_type} of map {map_id} while order {order_id} drives on it"
    return None


def _retry_conflict(
    action_type: str, parameters: Mapping[str, object], state: vda5050.State | None
) -> str | None:
    """retry/skipRetry name an action that is RETRIABLE right now (REFERENCE E.27)."""
    action_id = parameters.get("actionId")
    if not isinstance(action_id, str) or not action_id:
        return f"{action_type} needs the actionId of a RETRIABLE action"
    actions = state.action_states if state is not None else []
    if not any(a.action_id == action_id and is_retriable(a) for a in actions):
        return f"action {action_id} is not RETRIABLE"
    return None
