"""Vehicle-state webhooks: connection, operating mode and errors as `control` flushes them, and
orders a vehicle got or finished. Delivered like order events (signed, retried, logged).

`emit_vehicle_changes` runs in the flush, before the snapshots are saved, and compares them
with the stored rows; when nobody subscribed to vehicle events it costs one small query.
"""

import logging
from collections.abc import Sequence
from typing import Any

from django.db import transaction

from orders.services.webhooks import active_subscriptions, emit_event
from robots.models import Vehicle

logger = logging.getLogger(__name__)

VEHICLE_EVENTS = (
    "vehicle.connection_changed",
    "vehicle.mode_changed",
    "vehicle.error",
    "vehicle.order_assigned",
    "vehicle.order_finished",
)
_STATE_EVENTS = VEHICLE_EVENTS[:3]


def emit_vehicle_changes(*, snapshots: Sequence[dict[str, Any]]) -> int:
    """Emit an event per changed connection, changed operating mode and newly raised error type
    of the vehicles in `snapshots` (rows about to be saved). Never raises: a webhook problem
    must not stop the flush that keeps the fleet's state."""
    if not snapshots:
        return 0
    try:
        with transaction.atomic():
            return _emit(snapshots)
    except Exception:
        logger.exception("vehicle webhooks: could not record the events of a flush")
        return 0


def _emit(snapshots: Sequence[dict[str, Any]]) -> int:
    subscriptions = active_subscriptions()
    if not any(s.wants(event) for s in subscriptions for event in _STATE_EVENTS):
        return 0
    rows = {s["pk"]: s for s in snapshots if "pk" in s}
    emitted = 0
    for vehicle in Vehicle.objects.filter(pk__in=rows):
        row = rows[vehicle.pk]
        if "connection" in row and row["connection"] != vehicle.connection:
            emitted += _vehicle_event(
                "vehicle.connection_changed", vehicle, old=vehicle.connection, new=row["connection"]
            )
        mode = row.get("operating_mode")
        if mode and mode != vehicle.operating_mode:
            emitted += _vehicle_event(
                "vehicle.mode_changed", vehicle, old=vehicle.operating_mode, new=mode
            )
        known = {_error_key(e) for e in vehicle.errors or []}
        raised = [e for e in row.get("errors") or [] if _error_key(e) not in known]
        if raised:
            emitted += _vehicle_event("vehicle.error", vehicle, errors=raised)
    return emitted


def emit_vehicle_order_event(*, event_type: str, vehicle: Vehicle, order_id: int) -> int:
    """`vehicle.order_assigned` or `vehicle.order_finished` (call inside the change's
    transaction, like every event)."""
    return _vehicle_event(event_type, vehicle, order=order_id)


def _vehicle_event(event_type: str, vehicle: Vehicle, **detail: Any) -> int:
    def data() -> dict[str, Any]:
        return {
            "vehicle": {
                "id": vehicle.pk,
                "manufacturer": vehicle.manufacturer,
                "serial_number": vehicle.serial_number,
            },
            "detail": detail,
        }

    return emit_event(event_type=event_type, data=data)


def _error_key(error: Any) -> tuple[str, str]:
    if not isinstance(error, dict):
        return (str(error), "")
    return (str(error.get("errorType", "")), str(error.get("errorLevel", "")))
