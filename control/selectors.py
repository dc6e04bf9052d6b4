"""Reads for the live page (the database snapshot; the websocket brings what changed since)."""

from typing import Any

from control.traffic_support import vehicle_class
from maps.selectors import get_default_map, layout_as_dict
from orders.models import TransportOrder
from robots.models import Vehicle


def get_live_layout() -> dict[str, Any] | None:
    layout = get_default_map()
    return layout_as_dict(map=layout) if layout else None


def list_vehicle_rows() -> list[dict[str, Any]]:
    """Vehicles in the same shape as control's websocket rows (without the route)."""
    return [
        {
            "id": v.pk,
            "manufacturer": v.manufacturer,
            "serial": v.serial_number,
            "status": _status(v),
            "connection": v.connection,
            "x": v.x,
            "y": v.y,
            "theta": v.theta,
            "map": v.map_id,
            "size": _footprint(v.factsheet),
            "battery": v.battery_charge,
            "mode": v.operating_mode,
            "order": v.order_id,
            "transport_order": None,
            "last_node": v.last_node_id,
            "loaded": bool(v.loads),
            "errors": [f"{e.get('errorLevel')} {e.get('errorType')}" for e in v.errors or []],
            "base": [],
            "horizon": [],
        }
        for v in Vehicle.objects.all()
    ]


def list_order_rows(limit: int = 50) -> list[dict[str, Any]]:
    """The open orders and the most recent closed ones, newest first."""
    orders = TransportOrder.objects.select_related("source", "destination", "vehicle")
    rows = list(
        orders.filter(status__in=TransportOrder.OPEN_STATUSES).order_by("-created_at")[:limit]
    )
    rows += list(
        orders.exclude(status__in=TransportOrder.OPEN_STATUSES).order_by("-finished_at")[:limit]
    )
    return [
        {
            "id": o.pk,
            "status": o.status,
            "source": str(o.source),
            "destination": str(o.destination),
            "vehicle": o.vehicle.serial_number if o.vehicle else None,
            "created_at": o.created_at.isoformat(),
            "finished_at": o.finished_at.isoformat() if o.finished_at else None,
            "failure_reason": o.failure_reason,
        }
        for o in rows
    ]


def _footprint(factsheet: dict[str, Any] | None) -> list[float]:
    """Length and width the map draws, as control's rows give them."""
    footprint = vehicle_class(factsheet)
    return [round(footprint.length, 2), round(footprint.width, 2)]


def _status(vehicle: Vehicle) -> str:
    if vehicle.connection != Vehicle.Connection.ONLINE:
        return "offline"
    if vehicle.has_fatal_error:
        return "error"
    if vehicle.paused:
        return "paused"
    if vehicle.charging:
        return "charging"
    # The stored order id stays after an order ends, so it cannot tell busy from idle; the
    # live updates from control can.
    return "driving" if vehicle.driving else "idle"
