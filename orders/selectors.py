"""Reads for dispatch and control."""

from django.db.models import QuerySet

from orders.models import TransportOrder
from robots.models import Vehicle


def list_pending_orders() -> QuerySet[TransportOrder]:
    """Orders waiting for a vehicle, most urgent first."""
    return (
        TransportOrder.objects.filter(status=TransportOrder.Status.NEW, cancel_requested=False)
        .select_related("source__node", "source__map", "destination__node")
        .order_by("-priority", "created_at", "pk")
    )


def list_idle_vehicles() -> list[Vehicle]:
    """Vehicles dispatch may give work now: available and without an active transport order."""
    busy = TransportOrder.objects.filter(
        status__in=TransportOrder.ACTIVE_STATUSES, vehicle__isnull=False
    ).values("vehicle_id")
    candidates = Vehicle.objects.filter(connection=Vehicle.Connection.ONLINE).exclude(pk__in=busy)
    return [vehicle for vehicle in candidates if vehicle.is_available]


def list_active_orders() -> QuerySet[TransportOrder]:
    """Orders that a vehicle is assigned to or driving: what `control` executes."""
    return TransportOrder.objects.filter(status__in=TransportOrder.ACTIVE_STATUSES).select_related(
        "vehicle", "source__node", "destination__node", "source__map"
    )
