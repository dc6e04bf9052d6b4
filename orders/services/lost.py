"""The lost-vehicle policy: what happens to the orders of a vehicle that is gone.

A vehicle is lost while it is offline, unreachable or its connection broke, has a FATAL error,
or is in manual mode. VDA 5050 vehicles keep their order through such gaps, so the default is to
wait; integrators who would rather have the work done by another vehicle choose "reassign"
(only orders the vehicle never received can move safely) or "fail". Every step is recorded on
the order's timeline, with the reason.
"""

from datetime import datetime, timedelta

from django.db import transaction
from django.utils import timezone

from orders.conf import setting
from orders.models import OrderEvent, TransportOrder
from orders.services.dispatch import release_assignment
from orders.services.events import record
from orders.services.transport import cancel_transport_order, mark_order_failed
from robots.models import Vehicle

Kind = OrderEvent.Kind
POLICIES = ("wait", "reassign", "fail")
GONE = {
    Vehicle.Connection.UNREACHABLE,
    Vehicle.Connection.OFFLINE,
    Vehicle.Connection.CONNECTIONBROKEN,
}
MANUAL_MODES = {"MANUAL", "SERVICE", "TEACHIN"}


def lost_reason(vehicle: Vehicle) -> str | None:
    """Why the vehicle cannot go on with its orders now, or None if it can."""
    if vehicle.connection in GONE:
        return f"{vehicle} is {vehicle.get_connection_display()}"
    if vehicle.has_fatal_error:
        return f"{vehicle} has a FATAL error"
    if vehicle.operating_mode in MANUAL_MODES:
        return f"{vehicle} is in {vehicle.operating_mode} mode"
    return None


def handle_lost_vehicles(*, now: datetime | None = None) -> list[int]:
    """Apply FLEET_ORDERS LOST_VEHICLE_POLICY to the active orders; return the ids it acted on."""
    now = now or timezone.now()
    policy = setting("LOST_VEHICLE_POLICY")
    if policy not in POLICIES:
        raise ValueError(f"LOST_VEHICLE_POLICY must be one of {POLICIES}, not {policy!r}")
    grace = timedelta(seconds=float(setting("LOST_VEHICLE_GRACE")))
    acted = []
    orders = TransportOrder.objects.filter(
        status__in=TransportOrder.ACTIVE_STATUSES, vehicle__isnull=False
    ).select_related("vehicle")
    for order in orders:
        assert order.vehicle is not None  # filtered above
        reason = lost_reason(order.vehicle)
        if reason is None:
            if order.vehicle_lost_at is not None:
                _set_lost(order, None)
                record(order.pk, Kind.UPDATED, vehicle_back=str(order.vehicle))
        elif order.vehicle_lost_at is None:
            _set_lost(order, now)
            record(order.pk, Kind.UPDATED, vehicle_lost=reason, policy=policy)
        elif now - order.vehicle_lost_at >= grace and _apply(order, policy, reason, grace):
            acted.append(order.pk)
    return acted


def _set_lost(order: TransportOrder, at: datetime | None) -> None:
    TransportOrder.objects.filter(pk=order.pk).update(vehicle_lost_at=at)


@transaction.atomic
def _apply(order: TransportOrder, policy: str, reason: str, grace: timedelta) -> bool:
    why = f"{reason} for {grace.total_seconds():.0f} s (lost-vehicle policy {policy})"
    never_received = order.status == TransportOrder.Status.ASSIGNED and order.sent_at is None
    if policy == "reassign" and never_received:
        return release_assignment(order, why)
    if policy == "fail" and never_received:
        mark_order_failed(order_id=order.pk, reason=why)
        return True
    if policy == "fail" and not order.cancel_requested:
        cancel_transport_order(order=order, reason=why)
        return True
    return False
