"""How a virtual vehicle takes in an order message (REFERENCE §3 B and C, vehicle side).

:func:`receive` first lets the vehicle's misbehaviour act (drop, reject, delay), ignores an
identical resend, then :func:`process` applies the protocol: operating mode, new order or
update (stitching at the last base node), validation. A refusal becomes a WARNING error
that references orderId and orderUpdateId.

3.0 vehicles (REFERENCE §3 A.8, B.14, C.18) additionally reject a new order whose
orderUpdateId is not 0 and a resend of the current (orderId, orderUpdateId) whose content
differs (SAME_ORDER_UPDATE_ID), and report the 3.0 error types.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from simulator.orders import (
    OrderRejected,
    build_steps,
    check_actions,
    check_start,
    check_structure,
    resolve_targets,
)
from vda5050 import ErrorReference, Order, v3
from vda5050.enums import ErrorType, OperatingMode

if TYPE_CHECKING:
    from simulator.vehicle import VirtualVehicle

#: Modes in which the vehicle takes orders and instant actions (REFERENCE §3 I.39-40).
ORDER_MODES = frozenset({OperatingMode.AUTOMATIC, OperatingMode.SEMIAUTOMATIC})


def receive(vehicle: VirtualVehicle, order: Order) -> bool:
    """An order message arrived; returns True if it was accepted right away."""
    saboteur = vehicle.saboteur
    if saboteur.drop_order(order):
        return False  # as if it never arrived: no state, no error
    vehicle.mark_state_due()
    key = (order.order_id, order.order_update_id)
    if vehicle.order_id and key == (vehicle.order_id, vehicle.order_update_id):
        if vehicle.config.major >= 3 and not _same_content(order, vehicle.last_order):
            text = "same orderId and orderUpdateId as the current order, but other content"
            same_id = v3.ErrorType.SAME_ORDER_UPDATE_ID
            reject(vehicle, order, OrderRejected(ErrorType.ORDER_UPDATE_ERROR, text, same_id))
        return False  # resend of what we already run: ignore (REFERENCE §3 B.14)
    if saboteur.is_deferred(order):
        return False  # resend of what we queued
    error_type = saboteur.rejection(order)
    if error_type is not None:
        reject(vehicle, order, OrderRejected(error_type, "rejected by simulated misbehaviour"))
        return False
    if saboteur.defer(order):
        return False
    return process(vehicle, order)


def process(vehicle: VirtualVehicle, order: Order) -> bool:
    """Accept or reject an order/update by the protocol; True if accepted."""
    vehicle.mark_state_due()
    new_order = order.order_id != vehicle.order_id or not vehicle.order_id
    try:
        if vehicle.operating_mode not in ORDER_MODES:
            raise OrderRejected(
                ErrorType.ORDER_ERROR,
                f"operating mode {vehicle.operating_mode} accepts no orders",
                v3.ErrorType.MOBILE_ROBOT_NOT_AVAILABLE,
            )
        if new_order:
            _accept_new(vehicle, order)
        elif order.order_update_id == vehicle.order_update_id:
            return False  # a deferred copy of what is running now
        else:
            _accept_update(vehicle, order)
    except OrderRejected as rejected:
        reject(vehicle, order, rejected)
        return False
    vehicle.order_errors.clear()
    if new_order:
        vehicle.action_errors.clear()
    vehicle.cancelled = False
    vehicle.last_order = order
    return True


def _same_content(order: Order, previous: Order | None) -> bool:
    """True if ``order`` repeats ``previous`` apart from the header."""
    return previous is not None and (order.nodes, order.edges) == (previous.nodes, previous.edges)


def _accept_new(vehicle: VirtualVehicle, order: Order) -> None:
    major = vehicle.config.major
    if not vehicle.idle:
        raise OrderRejected(
            ErrorType.ORDER_ERROR,
            f"vehicle is busy with order {vehicle.order_id!r}; cancel it or wait until idle",
            v3.ErrorType.OTHER_ORDER_ACTIVE,
        )
    check_structure(order)
    if order.nodes[0].sequence_id != 0:
        raise OrderRejected(ErrorType.VALIDATION_ERROR, "new order must start at sequenceId 0")
    if major >= 3 and order.order_update_id != 0:
        raise OrderRejected(ErrorType.VALIDATION_ERROR, "new order must have orderUpdateId 0")
    targets = resolve_targets(order, vehicle.maps, vehicle.known_nodes)
    check_start(
        order, targets[0], vehicle.position, vehicle.last_node_id, vehicle.config.start_reach
    )
    check_actions(order, skip_first_node=False, major=major)
    vehicle.order_id = order.order_id
    vehicle.order_update_id = order.order_update_id
    vehicle.pending = build_steps(order, targets, include_first=True)
    vehicle.actions.reset_for_new_order(vehicle.pending)


def _accept_update(vehicle: VirtualVehicle, order: Order) -> None:
    if order.order_update_id < vehicle.order_update_id:
        raise OrderRejected(
            ErrorType.ORDER_UPDATE_ERROR,
            f"orderUpdateId {order.order_update_id} is older than {vehicle.order_update_id}",
        )
    if vehicle.cancelled:
        raise OrderRejected(
            ErrorType.ORDER_UPDATE_ERROR,
            "order was cancelled or cleared; send a new orderId",
            v3.ErrorType.ORDER_UPDATE_FOLLOWING_CANCEL,
        )
    check_structure(order)
    targets = resolve_targets(order, vehicle.maps, vehicle.known_nodes)
    pending = vehicle.pending
    released = [i for i, step in enumerate(pending) if step.released]
    stitch = order.nodes[0]
    if released:
        keep = released[-1] + 1
        expected = pending[keep - 1].key
    else:
        keep = 0
        expected = (vehicle.last_node_id, vehicle.last_node_sequence_id)
    if (stitch.node_id, stitch.sequence_id) != expected:
        raise OrderRejected(
            ErrorType.ORDER_UPDATE_ERROR,
            f"update starts at {stitch.node_id!r}/{stitch.sequence_id}, "
            f"expected last base node {expected[0]!r}/{expected[1]}",
            v3.ErrorType.VALIDATION_FAILURE,
        )
    check_actions(order, skip_first_node=True, major=vehicle.config.major)
    # Base is immutable, horizon is replaced; the stitching node keeps its first-sent
    # content (2.1 §6.6.2), so only the elements after it are appended.
    dropped = pending[keep:]
    vehicle.pending = pending[:keep] + build_steps(order, targets, include_first=False)
    vehicle.actions.replace_horizon(dropped, vehicle.pending[keep:])
    vehicle.order_update_id = order.order_update_id


def reject(vehicle: VirtualVehicle, order: Order, rejected: OrderRejected) -> None:
    """Report a refused order as a WARNING error referencing orderId and orderUpdateId."""
    refs = [
        ErrorReference(reference_key="orderId", reference_value=order.order_id),
        ErrorReference(reference_key="orderUpdateId", reference_value=str(order.order_update_id)),
    ]
    error_type = vehicle.error_type(rejected.error_type, rejected.v3_type)
    vehicle.add_order_error(error_type, rejected.description, refs)
