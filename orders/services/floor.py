"""Where orders meet inventory and alerts (issue 8): this module is the orders layer's glue.

Inventory and alerts sit below orders and beside each other, so neither may call the other;
this module (and only it) connects them: pick/drop steps update the stock, failed and late
orders raise alerts, inventory discrepancies and due maintenance work become alerts, and the
ERP's "move load L to station S" becomes a transport order. Every hook is defensive: a bug or
outage here is logged and must never undo or block the order progress that triggered it.
"""

import logging
import time
from collections.abc import Mapping, Sequence
from typing import Any

from django.db import transaction
from django.utils import timezone

from alerts import services as alert_services
from alerts.models import Severity, Source
from fleet.exceptions import InvalidRequestError
from inventory import selectors as inventory_selectors
from inventory import services as inventory_services
from maintenance import selectors as maintenance_selectors
from maps.models import Station
from orders.models import OrderStep, TransportOrder

logger = logging.getLogger(__name__)

LATE_CHECK_SECONDS = 30.0  # how often the flush hook looks for orders past their deadline
_late_checked_at = [float("-inf")]


def order_ref(order: TransportOrder) -> str:
    """How alerts name an order: the ERP's reference if there is one, else our id."""
    return order.external_ref or f"TO-{order.pk}"


def observe_fleet(*, snapshots: Sequence[Mapping[str, Any]]) -> None:
    """After each `control` flush: snapshot alerts, state.loads vs inventory, late orders.

    Called once per flush (at most every second) from `control.persistence`; never raises.
    """
    try:
        alert_services.observe_snapshots(snapshots=snapshots)
        inventory_services.observe_loads(snapshots=snapshots)
        sync_inventory_alerts()
        now = time.monotonic()
        if now - _late_checked_at[0] >= LATE_CHECK_SECONDS:
            _late_checked_at[0] = now
            check_late_orders()
            sync_maintenance_alerts()
    except Exception:
        logger.exception("alert/inventory observation failed; the next flush retries")


def sync_inventory_alerts() -> tuple[int, int]:
    """One open alert per open inventory discrepancy; resolved with it (cause = its key)."""
    active = {
        d.key: {
            "source": Source.INVENTORY,
            "severity": Severity.WARNING,
            "message": d.message,
            "vehicle": d.vehicle_id,
            "order_ref": d.order_ref,
            "details": {"kind": d.kind, "load": d.load_id},
        }
        for d in inventory_selectors.open_discrepancies()
    }
    return alert_services.sync_causes(prefixes=["inv:"], active=active)


def check_late_orders() -> tuple[int, int]:
    """Raise ORDER_LATE for open orders past their deadline; resolve it when they close."""
    now = timezone.now()
    late = TransportOrder.objects.filter(
        status__in=TransportOrder.OPEN_STATUSES, deadline__lt=now
    ).only("pk", "external_ref", "deadline", "vehicle_id", "status")
    active = {
        f"order_late:{order.pk}": {
            "source": Source.ORDER_LATE,
            "severity": Severity.WARNING,
            "message": f"order {order_ref(order)} is past its deadline "
            f"{order.deadline:%H:%M:%S} and still {order.get_status_display()}",
            "vehicle": order.vehicle_id,
            "order_ref": order_ref(order),
        }
        for order in late
    }
    return alert_services.sync_causes(prefixes=["order_late:"], active=active)


def sync_maintenance_alerts() -> tuple[int, int]:
    """One alert per work order that is due and not yet taken up (DUE/OPEN, due time passed);
    URGENT once maintenance marked it overdue; resolved when work starts or is done."""
    now = timezone.now()
    waiting = maintenance_selectors.list_open_work_orders().filter(
        status__in=["DUE", "OPEN"], due_at__lte=now
    )
    overdue = set(maintenance_selectors.list_overdue_work_orders().values_list("pk", flat=True))
    active = {
        f"maintenance:{work.pk}": {
            "source": Source.MAINTENANCE,
            "severity": Severity.URGENT if work.pk in overdue else Severity.WARNING,
            "message": f"maintenance {'overdue' if work.pk in overdue else 'due'}: {work.title}"
            f" on {work.vehicle}",
            "vehicle": work.vehicle_id,
            "details": {"work_order": work.pk, "trigger": work.trigger},
        }
        for work in waiting
    }
    return alert_services.sync_causes(prefixes=["maintenance:"], active=active)


def on_step_finished(*, step: OrderStep) -> None:
    """A pick or drop finished: the stock follows (inside a savepoint that cannot fail ours)."""
    vehicle_id = step.order.vehicle_id
    if vehicle_id is None or step.operation not in (OrderStep.Operation.PICK, "DROP"):
        return
    load_id = str((step.parameters or {}).get("loadId") or step.order.load_id or "")
    ref = order_ref(step.order)
    try:
        with transaction.atomic():
            if step.operation == OrderStep.Operation.PICK:
                inventory_services.record_pick(
                    vehicle_id=vehicle_id,
                    station_id=step.station_id,
                    load_id=load_id,
                    load_type=step.order.load_type,
                    order_ref=ref,
                )
            else:
                inventory_services.record_drop(
                    vehicle_id=vehicle_id,
                    station_id=step.station_id,
                    load_id=load_id,
                    order_ref=ref,
                )
    except Exception:
        logger.exception("inventory update for %s step %s failed", ref, step.index)


def on_order_failed(*, order_id: int, reason: str) -> None:
    """A failed order always needs a person: raise an URGENT alert (resolved by hand)."""
    order = TransportOrder.objects.filter(pk=order_id).first()
    if order is None:
        return
    try:
        with transaction.atomic():
            alert_services.raise_alert(
                cause=f"order_failed:{order.pk}",
                source=Source.ORDER_FAILED,
                severity=Severity.URGENT,
                message=f"order {order_ref(order)} failed: {reason[:300]}",
                vehicle=order.vehicle_id,
                order_ref=order_ref(order),
            )
    except Exception:
        logger.exception("could not raise the alert of failed order %s", order_id)


def on_order_closed(*, order_id: int) -> None:
    """A finished or cancelled order is no longer late."""
    try:
        with transaction.atomic():
            alert_services.resolve_alert(f"order_late:{order_id}")
    except Exception:
        logger.exception("could not resolve the late alert of order %s", order_id)


def move_load_to(*, load_id: str, destination: Station, **order_fields: Any) -> TransportOrder:
    """The ERP's "move load L to station S": the inventory knows the source.

    Raises InvalidRequestError when the load is unknown, on a vehicle or nowhere known.
    """
    from orders.services.transport import create_transport_order

    load = inventory_selectors.find_load(load_id)
    if load is None:
        raise InvalidRequestError(f"load {load_id!r} is not in the inventory")
    if load.location is None:
        raise InvalidRequestError(f"load {load_id!r} is at {load.place}, not at a station")
    source = load.location.station
    if source.pk == destination.pk:
        raise InvalidRequestError(f"load {load_id!r} is already at {destination.station_id}")
    return create_transport_order(
        source=source,
        destination=destination,
        load_id=load.load_id,
        load_type=load.load_type,
        **order_fields,
    )
