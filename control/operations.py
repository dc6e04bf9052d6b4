"""Reads for the operations pages: the fleet overview and the vehicles list.

`control` is the top layer, so it may combine what the apps below know about a vehicle: its
snapshot (robots), its active order (orders), its layout vehicle type (orders' factsheet match),
whether it is out of service (maintenance), charging points (battery) and open alerts (alerts).
Each page costs a fixed handful of queries, whatever the fleet's size.
"""

from collections import Counter
from dataclasses import dataclass
from datetime import datetime, time
from typing import Any

from django.db.models import Sum
from django.urls import NoReverseMatch, reverse
from django.utils import timezone

from alerts import selectors as alert_selectors
from alerts.models import SEVERITY_RANK, Severity
from battery.models import Charger, ChargeSession
from maintenance import selectors as maintenance_selectors
from orders import selectors as order_selectors
from orders.models import TransportOrder
from robots.models import Vehicle

WORKING_MODES = {"AUTOMATIC", "SEMIAUTOMATIC"}

# The overview's vehicle states, in the order the page shows them (worst reasons first wins).
VEHICLE_STATES: list[tuple[str, str]] = [
    ("driving", "driving or working an order"),
    ("idle", "idle"),
    ("charging", "charging"),
    ("error", "in a fatal error"),
    ("offline", "offline"),
    ("manual", "manual mode or paused"),
    ("out_of_service", "out of service"),
]
STATE_LABELS = dict(VEHICLE_STATES)
STATE_BADGES = {state: state.replace("_", " ") for state, _ in VEHICLE_STATES}  # list badges
CONNECTIONS = Vehicle.Connection.choices


def vehicle_state(vehicle: Vehicle, *, busy: set[int], out_of_service: set[int]) -> str:
    """One of VEHICLE_STATES for a vehicle row. Out of service beats everything (dispatch does
    not use it whatever it reports), then offline, error, manual/paused, charging, working."""
    if vehicle.pk in out_of_service:
        return "out_of_service"
    if vehicle.connection != Vehicle.Connection.ONLINE:
        return "offline"
    if vehicle.has_fatal_error:
        return "error"
    if vehicle.paused or (vehicle.operating_mode and vehicle.operating_mode not in WORKING_MODES):
        return "manual"
    if vehicle.charging:
        return "charging"
    if vehicle.driving or vehicle.pk in busy:
        return "driving"
    return "idle"


def vehicle_url(vehicle: Vehicle) -> str:
    """The vehicle page (`control:vehicle-detail`), or its path pattern before that page exists."""
    try:
        return reverse("control:vehicle-detail", args=[vehicle.manufacturer, vehicle.serial_number])
    except NoReverseMatch:
        return f"/vehicles/{vehicle.manufacturer}/{vehicle.serial_number}/"


@dataclass(frozen=True)
class VehicleRow:
    """One line of the vehicles list."""

    pk: int
    name: str
    manufacturer: str
    serial: str
    state: str
    vehicle_type: str
    connection: str
    battery: float | None
    mode: str
    last_node: str
    order: int | None
    errors: list[str]
    last_seen: datetime | None
    url: str
    note: str = ""

    @property
    def state_label(self) -> str:
        return STATE_BADGES[self.state]

    @property
    def identity(self) -> str:
        return f"{self.manufacturer}/{self.serial}"


def list_vehicles() -> list[VehicleRow]:
    """Every vehicle with its operations state, type, active order and why it is out of service."""
    vehicles = list(Vehicle.objects.all())
    active = dict(
        TransportOrder.objects.filter(
            status__in=TransportOrder.ACTIVE_STATUSES, vehicle__isnull=False
        ).values_list("vehicle_id", "pk")
    )
    held = maintenance_selectors.out_of_service(vehicle_ids=[v.pk for v in vehicles])
    types = order_selectors.get_vehicle_types(vehicles=vehicles)
    busy, out_of_service = set(active), set(held)
    return [
        VehicleRow(
            pk=v.pk,
            name=str(v),
            manufacturer=v.manufacturer,
            serial=v.serial_number,
            state=vehicle_state(v, busy=busy, out_of_service=out_of_service),
            vehicle_type=types[v.pk].type_id if v.pk in types else "",
            connection=v.connection,
            battery=v.battery_charge,
            mode=v.operating_mode,
            last_node=v.last_node_id,
            order=active.get(v.pk),
            errors=[f"{e.get('errorLevel')} {e.get('errorType')}" for e in v.errors or []],
            last_seen=v.last_seen,
            url=vehicle_url(v),
            note=held.get(v.pk, ""),
        )
        for v in vehicles
    ]


@dataclass(frozen=True)
class VehicleQuery:
    """The vehicles list's filters and sort (validated by the view's form)."""

    state: str = ""
    vehicle_type: str = ""
    connection: str = ""
    battery_below: float | None = None
    search: str = ""
    sort: str = "serial"
    descending: bool = False


SORT_KEYS: dict[str, Any] = {
    "serial": lambda r: (r.serial.lower(), r.manufacturer),
    "state": lambda r: ([s for s, _ in VEHICLE_STATES].index(r.state), r.serial),
    "type": lambda r: (r.vehicle_type, r.serial),
    "connection": lambda r: (r.connection, r.serial),
    "battery": lambda r: (r.battery is None, r.battery or 0.0, r.serial),
    "last_seen": lambda r: (r.last_seen is None, r.last_seen or timezone.now(), r.serial),
}


def filter_vehicles(rows: list[VehicleRow], query: VehicleQuery) -> list[VehicleRow]:
    """Rows matching every filter of `query`, in its order."""
    search = query.search.strip().lower()
    kept = [
        r
        for r in rows
        if (not query.state or r.state == query.state)
        and (not query.vehicle_type or r.vehicle_type == query.vehicle_type)
        and (not query.connection or r.connection == query.connection)
        and (
            query.battery_below is None
            or (r.battery is not None and r.battery < query.battery_below)
        )
        and (not search or search in r.serial.lower() or search in r.name.lower())
    ]
    return sorted(kept, key=SORT_KEYS[query.sort], reverse=query.descending)


@dataclass(frozen=True)
class Overview:
    """The figures of the fleet overview."""

    vehicles: list[tuple[str, str, int]]  # state, label, count
    vehicle_total: int
    orders: list[tuple[str, str, int]]  # status, label, count (open ones, then today's ends)
    alerts: list[tuple[str, str, int]]  # severity, label, count (worst first)
    alert_total: int
    charging_points: int
    points_in_use: int
    charge_queue: int
    out_of_service: list[VehicleRow]


def get_overview(*, now: datetime | None = None) -> Overview:
    """Counts of vehicles by state, orders by status, open alerts by severity, chargers."""
    rows = list_vehicles()
    by_state = Counter(r.state for r in rows)
    today = timezone.make_aware(
        datetime.combine(timezone.localdate(now or timezone.now()), time.min)
    )
    open_counts = Counter(
        TransportOrder.objects.filter(status__in=TransportOrder.OPEN_STATUSES).values_list(
            "status", flat=True
        )
    )
    ended_today = Counter(
        TransportOrder.objects.filter(finished_at__gte=today)
        .exclude(status__in=TransportOrder.OPEN_STATUSES)
        .values_list("status", flat=True)
    )
    labels = dict(TransportOrder.Status.choices)
    orders = [(s, labels[s], open_counts[s]) for s in TransportOrder.OPEN_STATUSES] + [
        (s, f"{labels[s]} today", ended_today[s]) for s in ("FINISHED", "FAILED", "CANCELLED")
    ]
    severities = Counter(alert_selectors.open_alerts().values_list("severity", flat=True))
    alerts = [
        (s.value, s.label, severities[s.value])
        for s in sorted(Severity, key=lambda s: -SEVERITY_RANK[s.value])
    ]
    active_chargers = Charger.objects.filter(is_active=True)
    return Overview(
        vehicles=[(state, label, by_state[state]) for state, label in VEHICLE_STATES],
        vehicle_total=len(rows),
        orders=orders,
        alerts=alerts,
        alert_total=sum(severities.values()),
        charging_points=active_chargers.aggregate(n=Sum("capacity"))["n"] or 0,
        points_in_use=ChargeSession.objects.filter(
            status__in=[ChargeSession.Status.CHARGING, ChargeSession.Status.STOPPING]
        ).count(),
        charge_queue=ChargeSession.objects.filter(
            status__in=[
                ChargeSession.Status.QUEUED,
                ChargeSession.Status.ASSIGNED,
                ChargeSession.Status.DRIVING,
            ]
        ).count(),
        out_of_service=[r for r in rows if r.state == "out_of_service"],
    )
