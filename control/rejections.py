"""Why a vehicle rejected an order, from the error that references it (REFERENCE B.15, C.17-18).

2.x vehicles name a few error types (`validationError`, `orderError`, `orderUpdateError`,
`noOrderToCancel`) and leave the rest to the vendor: their reason is the error type and the
vehicle's description, as before. 3.0 predefines one error type per cause (C.18); each gets
its own explanation on the transport order, so an operator can tell a malformed order from a
missing route, an unsupported action or a vehicle that is simply busy.
"""

import vda5050

# 3.0 §6.6.5.2 predefined rejection types (REFERENCE §3 C.18) and what they mean for us.
V3_REASONS: dict[str, str] = {
    "VALIDATION_FAILURE": "the order failed the vehicle's validation",
    "UNSUPPORTED_PARAMETER": "the order uses a parameter the vehicle does not support",
    "INVALID_ORDER_ACTION": "an action of the order cannot be executed by the vehicle",
    "INVALID_ORDER": "an action of the order cannot be executed by the vehicle",
    "OUTDATED_ORDER_UPDATE": "the update is older than the one the vehicle runs",
    "SAME_ORDER_UPDATE_ID": "a resend differed from the update the vehicle already has",
    "ORDER_UPDATE_FOLLOWING_CANCEL": "the order was cancelled; it cannot be updated",
    "OTHER_ORDER_ACTIVE": "the vehicle is busy with another order",
    "START_NODE_OUT_OF_RANGE": "the vehicle is not at the order's first node",
    "NO_ROUTE_TO_TARGET": "the vehicle finds no route to the order's nodes",
    "MOBILE_ROBOT_NOT_AVAILABLE": "the vehicle takes no orders right now",
    "UNKNOWN_MAP_ID": "the order uses a map the vehicle does not have",
    "INSUFFICIENT_MEMORY": "the order is too large for the vehicle's memory",
}


def rejection_reason(error: vda5050.Error) -> str:
    """The reason recorded on a transport order the vehicle rejected with `error`."""
    text = f"{error.error_type} {error.error_description or ''}".strip()
    meaning = V3_REASONS.get(str(error.error_type))
    if meaning is None:
        return f"rejected by vehicle: {text}"  # 2.x and vendor types, unchanged
    return f"rejected by vehicle: {text} ({meaning})"
