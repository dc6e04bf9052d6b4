"""Reads for dispatch, control, the API and webhooks."""

from collections import Counter
from dataclasses import dataclass, field
from datetime import datetime, timedelta
from typing import Any

from django.db.models import F, Max, Prefetch, Q, QuerySet

from maps.models import VehicleType
from orders import capability
from orders.models import (
    OrderSequence,
    OrderStep,
    TransportOrder,
    VehicleCommand,
    WebhookDelivery,
    WebhookSubscription,
)
from robots.models import Vehicle

Status = TransportOrder.Status


def list_pending_orders() -> list[TransportOrder]:
    """Orders waiting for a vehicle, most urgent first (priority, deadline, age), with steps.

    Ranked here, not by the database: Django compiled the ORDER BY (an expression, for
    deadlines last when missing on every database) against each of the hundred joined columns,
    about a third of every dispatch cycle's SQL compiling under load (docs/LOAD.md, twelfth
    round). The intended vehicle and vehicle type, named only in notes and rarely set, come
    from their own reads, which run only when an order has one."""
    orders = list(
        TransportOrder.objects.filter(status=Status.NEW, cancel_requested=False)
        .select_related("source__node", "source__map", "destination__node")
        .prefetch_related(
            "intended_vehicle",
            "vehicle_type",
            Prefetch("steps", queryset=OrderStep.objects.select_related("station__node")),
        )
        .order_by()  # not even the model's default: ranked below
    )
    orders.sort(key=_urgency)
    return orders


def _urgency(order: TransportOrder) -> tuple[Any, ...]:
    """Sort key: higher priority, then the earlier deadline (none last), then the older."""
    deadline = (0, order.deadline) if order.deadline is not None else (1,)
    return (-order.priority, deadline, order.created_at, order.pk)


@dataclass
class SequenceGate:
    """How order sequences constrain a dispatch cycle: orders that wait for an earlier order of
    their sequence (with the note), the vehicle each sequence is bound to, and the vehicles
    reserved by sequences that still have open orders."""

    waiting: dict[int, str] = field(default_factory=dict)
    vehicle_of: dict[int, int] = field(default_factory=dict)  # sequence -> vehicle
    reserved: dict[int, int] = field(default_factory=dict)  # vehicle -> sequence


def get_sequence_gate(*, orders: list[TransportOrder]) -> SequenceGate:
    """The sequence constraints for `orders` (pending): one query when any order is in a
    sequence, two more for the reservations."""
    gate = SequenceGate()
    open_sequences = OrderSequence.objects.filter(
        vehicle__isnull=False, orders__status__in=TransportOrder.OPEN_STATUSES
    ).distinct()
    for sequence_pk, vehicle_pk in open_sequences.values_list("pk", "vehicle_id"):
        gate.vehicle_of[sequence_pk] = vehicle_pk
        gate.reserved[vehicle_pk] = sequence_pk
    sequenced = [o for o in orders if o.sequence_id is not None]
    if not sequenced:
        return gate
    first_open: dict[int, tuple[int, int]] = {}  # sequence -> (index, pk) of its first open
    rows = (
        TransportOrder.objects.filter(
            sequence_id__in={o.sequence_id for o in sequenced},
            status__in=TransportOrder.OPEN_STATUSES,
        )
        .order_by("sequence_id", "sequence_index")
        .values_list("sequence_id", "sequence_index", "pk")
    )
    for sequence_pk, index, pk in rows:
        first_open.setdefault(sequence_pk, (index or 0, pk))
    for order in sequenced:
        place = order.sequence_index or 0
        index, pk = first_open.get(order.sequence_id or 0, (place, order.pk))
        if pk != order.pk and index < place:
            gate.waiting[order.pk] = f"waits for order {pk} of its sequence"
    return gate


def get_vehicle_types(
    *, vehicles: list[Vehicle], types: list[VehicleType] | None = None
) -> dict[int, VehicleType]:
    """The layout vehicle type of each vehicle whose factsheet names a known one: the type id
    `manufacturer.seriesName` (LIF's convention) or `seriesName`, or a type with that
    manufacturer and series name. Vehicles of unknown type are left out. `types`: every
    vehicle type, when already read."""
    if types is None:
        types = list(VehicleType.objects.all())
    by_id = {t.type_id: t for t in types}
    by_series = {(t.manufacturer, t.series_name): t for t in types if t.series_name}
    found: dict[int, VehicleType] = {}
    for vehicle in vehicles:
        series = capability.series_name(vehicle.factsheet)
        if not series:
            continue
        match = (
            by_id.get(f"{vehicle.manufacturer}.{series}")
            or by_id.get(series)
            or by_series.get((vehicle.manufacturer, series))
            or by_series.get(("", series))
        )
        if match is not None:
            found[vehicle.pk] = match
    return found


def list_idle_vehicles() -> list[Vehicle]:
    """Vehicles dispatch may give work now: available and without an active transport order."""
    return get_dispatch_fleet().idle


@dataclass
class DispatchFleet:
    """The vehicles as dispatch sees them: the idle ones, and counts that explain the others."""

    idle: list[Vehicle] = field(default_factory=list)
    online: int = 0
    busy: int = 0
    unavailable: Counter[str] = field(default_factory=Counter)


def get_dispatch_fleet(
    *, held_since: datetime | None = None, with_factsheets: bool = True
) -> DispatchFleet:
    """Online vehicles split into idle (available, no active order), busy and unavailable (with
    the reason: paused, in error, manual mode, no position, or told to pause, charge or park by
    a command since `held_since`). Without factsheets the vehicles come with `factsheet`
    deferred (dispatch attaches the idle ones' from its cache)."""
    busy = set(
        TransportOrder.objects.filter(
            status__in=TransportOrder.ACTIVE_STATUSES, vehicle__isnull=False
        ).values_list("vehicle_id", flat=True)
    )
    held = list_held_vehicles(since=held_since) if held_since else {}
    fleet = DispatchFleet()
    online = Vehicle.objects.filter(connection=Vehicle.Connection.ONLINE)
    for vehicle in online if with_factsheets else online.defer("factsheet"):
        fleet.online += 1
        if not vehicle.is_available:
            fleet.unavailable[_unavailable_reason(vehicle)] += 1
        elif vehicle.pk in held:
            fleet.unavailable[held[vehicle.pk]] += 1
        elif vehicle.pk in busy:
            fleet.busy += 1
        else:
            fleet.idle.append(vehicle)
    return fleet


_HOLDING: dict[str, str] = {
    VehicleCommand.Kind.PAUSE: "told to pause",
    VehicleCommand.Kind.CHARGE: "sent to charge",
    VehicleCommand.Kind.PARK: "sent to park",
}


def list_held_vehicles(*, since: datetime) -> dict[int, str]:
    """Vehicles whose latest pause/resume/charge/park command since `since` holds them back
    from dispatch (anything but a resume), with the reason."""
    kinds = [*_HOLDING, str(VehicleCommand.Kind.RESUME)]
    latest: dict[int, str] = {}
    for vehicle_id, kind in (
        VehicleCommand.objects.filter(created_at__gte=since, kind__in=kinds)
        .order_by("created_at", "pk")
        .values_list("vehicle_id", "kind")
    ):
        latest[vehicle_id] = kind
    return {pk: _HOLDING[kind] for pk, kind in latest.items() if kind in _HOLDING}


def _unavailable_reason(vehicle: Vehicle) -> str:
    if vehicle.has_fatal_error:
        return "in error"
    if vehicle.paused:
        return "paused"
    if vehicle.operating_mode not in {"AUTOMATIC", "SEMIAUTOMATIC"}:
        return f"in {vehicle.operating_mode or 'unknown'} mode"
    return "without a position"


def get_idle_since(*, vehicle_ids: list[int]) -> dict[int, datetime]:
    """When each vehicle's last transport order ended (vehicles without one are left out)."""
    rows = (
        TransportOrder.objects.filter(vehicle_id__in=vehicle_ids, finished_at__isnull=False)
        .values("vehicle_id")
        .annotate(last=Max("finished_at"))
    )
    return {row["vehicle_id"]: row["last"] for row in rows}


def list_active_orders() -> QuerySet[TransportOrder]:
    """Orders that a vehicle is assigned to or driving: what `control` executes."""
    return (
        TransportOrder.objects.filter(status__in=TransportOrder.ACTIVE_STATUSES)
        # Not the vehicle row: control reads this every second and needs only vehicle_id
        # (the row's factsheet and state JSON cost more to decode than the rest together).
        .select_related("source__node", "destination__node", "source__map")
        .prefetch_related(
            Prefetch("steps", queryset=OrderStep.objects.select_related("station__node"))
        )
    )


STATE_GRACE = timedelta(seconds=5)  # a state this long after the assignment has had its chance


def list_stale_assignments(*, assigned_before: datetime) -> QuerySet[TransportOrder]:
    """Orders assigned before `assigned_before` that control has evidently not sent.

    Conservative on purpose: besides not started, not recorded as sent and not being cancelled,
    the vehicle must have reported a state after the assignment (plus a grace for control's
    flush) that does not name the order. A vehicle that has been silent since the assignment
    may have received the order and be driving it offline, so its order is left alone.
    """
    return (
        TransportOrder.objects.filter(
            status=Status.ASSIGNED,
            assigned_at__lt=assigned_before,
            started_at__isnull=True,
            sent_at__isnull=True,
            cancel_requested=False,
            vehicle__last_seen__gt=F("assigned_at") + STATE_GRACE,
        )
        .exclude(vehicle__order_id=F("vda_order_id"))
        .select_related("vehicle")
    )


def list_transport_orders(*, filters: dict[str, Any]) -> QuerySet[TransportOrder]:
    """Orders for the API, newest first, narrowed by the validated `filters` of the list call."""
    orders = TransportOrder.objects.select_related(
        "source", "destination", "vehicle", "intended_vehicle", "vehicle_type", "sequence"
    ).prefetch_related(
        "events", Prefetch("steps", queryset=OrderStep.objects.select_related("station"))
    )
    exact = {
        "status": "status",
        "source": "source__station_id",
        "destination": "destination__station_id",
        "vehicle": "vehicle__serial_number",
        "vehicle_id": "vehicle_id",
        "external_ref": "external_ref",
        "created_after": "created_at__gte",
        "created_before": "created_at__lt",
        "finished_after": "finished_at__gte",
        "finished_before": "finished_at__lt",
    }
    query = Q()
    for name, lookup in exact.items():
        if filters.get(name) not in (None, ""):
            query &= Q(**{lookup: filters[name]})
    return orders.filter(query).order_by("-created_at", "-pk")


def list_active_subscriptions() -> list[WebhookSubscription]:
    """Webhook subscriptions of active clients that are switched on."""
    return list(
        WebhookSubscription.objects.filter(is_active=True, client__is_active=True).select_related(
            "client"
        )
    )


def list_due_webhook_deliveries(*, now: datetime, limit: int) -> list[int]:
    """Ids of pending deliveries whose next attempt is due, oldest first."""
    return list(
        WebhookDelivery.objects.filter(
            status=WebhookDelivery.Status.PENDING, next_attempt_at__lte=now
        )
        .order_by("next_attempt_at")
        .values_list("pk", flat=True)[:limit]
    )
