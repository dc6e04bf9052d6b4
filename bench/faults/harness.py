"""What every fault row shares: its own services, Django on them, orders and the §3 verdict.

"Nothing lost" (RELIABILITY.md §3): every transport order we created ends in exactly one
terminal state with a complete event history; no (orderId, orderUpdateId) published with two
contents; no order on two vehicles (the observer's figures).
"""

import os
import random
import threading
import time
from collections import Counter
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass, field
from typing import Any

from bench.faults.fleet import Fleet, Observer, wait_until
from bench.faults.stack import Stack

TERMINAL = {"FINISHED", "FAILED", "CANCELLED"}


@dataclass
class Context:
    """One row's services, processes and observer."""

    stack: Stack
    fleet: Fleet
    observer: Observer
    full: bool
    layout: Any = None
    rng: random.Random = field(default_factory=lambda: random.Random(5050))

    def pick(self, quick: int, full: int) -> int:
        return full if self.full else quick


@contextmanager
def row_context(*, full: bool, appendonly: bool = True) -> Iterator[Context]:
    """Start the row's own services, point Django at them, load the demo layout."""
    stack = Stack(appendonly=appendonly)
    fleet: Fleet | None = None
    observer: Observer | None = None
    try:
        stack.start()
        os.environ.update(stack.env())
        os.environ["CELERY_TASK_ALWAYS_EAGER"] = "0"
        os.environ["DJANGO_SETTINGS_MODULE"] = "fleet.settings"  # not a test settings module
        import django

        django.setup()
        from battery.services import create_missing_chargers
        from maps.demo import warehouse_layout
        from maps.services import create_layout

        fleet = Fleet(stack)
        print(f"logs in {fleet.log_dir}", flush=True)
        os.environ["VDA5050_INTERFACE"] = fleet.interface
        observer = Observer(stack.mosquitto.url, fleet.interface)
        context = Context(stack=stack, fleet=fleet, observer=observer, full=full)
        context.layout = create_layout(spec=warehouse_layout(columns=6, rows=4))
        # The layout's two charge stations get chargers, as a site runs `create_chargers`: the
        # default charging policy then sends low vehicles to charge (beat's charging cycle), so
        # long rows do not stall on flat batteries ("battery low" holds every vehicle).
        create_missing_chargers()
        fleet.write_layout(context.layout)
        yield context
    finally:
        if observer is not None:
            observer.stop()
        if fleet is not None:
            codes = fleet.close()
            print(f"exit codes: {codes}")
        from django.db import connections

        connections.close_all()
        stack.close()


def online_vehicles() -> int:
    from robots.models import Vehicle

    return Vehicle.objects.filter(connection="ONLINE").count()


def wait_online(context: Context, count: int, timeout: float = 300) -> float:
    return wait_until(
        lambda: online_vehicles() >= count, timeout, f"{count} vehicles online", context.fleet
    )


def create_orders(context: Context, count: int) -> list[int]:
    """`count` pick → drop orders over the demo stations (through the services, as staff do)."""
    from maps.models import Station
    from orders.services import create_transport_order

    picks = list(Station.objects.filter(map=context.layout, kind=Station.Kind.PICK))
    drops = list(Station.objects.filter(map=context.layout, kind=Station.Kind.DROP))
    ids = []
    for _ in range(count):
        order = create_transport_order(
            source=context.rng.choice(picks),
            destination=context.rng.choice(drops),
            load_id=f"L{context.rng.randrange(10**6)}",
        )
        ids.append(order.pk)
    return ids


def open_count(ids: list[int]) -> int:
    from orders.models import TransportOrder

    return TransportOrder.objects.filter(
        pk__in=ids, status__in=TransportOrder.OPEN_STATUSES
    ).count()


class Feeder(threading.Thread):
    """Keeps `in_flight` orders open until `total` were created (a steady stream of work)."""

    def __init__(self, context: Context, total: int, in_flight: int) -> None:
        super().__init__(daemon=True)
        self.context, self.total, self.in_flight = context, total, in_flight
        self.ids: list[int] = []
        self.errors: list[str] = []
        self._halt = threading.Event()

    def run(self) -> None:
        from django.db import close_old_connections, connection

        try:
            while len(self.ids) < self.total and not self._halt.is_set():
                try:
                    missing = self.in_flight - open_count(self.ids)
                    if missing > 0:
                        batch = min(missing, self.total - len(self.ids))
                        self.ids.extend(create_orders(self.context, batch))
                except Exception as exc:  # noqa: BLE001 - a DB fault row expects some
                    self.errors.append(repr(exc))
                    close_old_connections()
                self._halt.wait(0.5)
        finally:
            connection.close()

    def stop(self) -> None:
        self._halt.set()
        self.join(10)


def wait_all_closed(context: Context, ids: list[int], timeout: float) -> float | None:
    try:
        return wait_until(lambda: open_count(ids) == 0, timeout, "all orders closed", context.fleet)
    except TimeoutError:
        return None


def verdict(context: Context, ids: list[int]) -> dict[str, Any]:
    """§3 "nothing lost" for `ids` plus the observer's publish figures."""
    from orders.models import OrderEvent, TransportOrder

    orders = TransportOrder.objects.filter(pk__in=ids)
    statuses = Counter(orders.values_list("status", flat=True))
    incomplete = 0
    for order in orders.prefetch_related("events"):
        kinds = [e.kind for e in sorted(order.events.all(), key=lambda e: (e.at, e.pk))]
        terminal_events = [k for k in kinds if k in TERMINAL]
        if order.status in TERMINAL and (
            not kinds or kinds[0] != OrderEvent.Kind.CREATED or terminal_events != [order.status]
        ):
            incomplete += 1
    figures: dict[str, Any] = {
        "orders": len(ids),
        "statuses": dict(statuses),
        "lost_orders": len(ids) - sum(statuses[s] for s in TERMINAL),
        "incomplete_histories": incomplete,
        **context.observer.figures(),
        **charging_figures(),
    }
    figures["all_finished"] = statuses.get("FINISHED", 0) == len(ids)
    figures["nothing_lost"] = (
        figures["lost_orders"] == 0
        and incomplete == 0
        and figures["duplicate_content_order_publishes"] == 0
        and figures["orders_sent_to_two_vehicles"] == 0
    )
    return figures


def charging_figures() -> dict[str, Any]:
    """Charge sessions of the row by status and the lowest charge any vehicle reported during
    the row (battery samples, taken on every 1 % change) and at its end: a row that runs long
    enough to need charging shows sessions DONE and a lowest charge above the critical level."""
    from django.db.models import Min

    from battery.models import BatterySample, ChargeSession
    from robots.models import Vehicle

    sessions = Counter(ChargeSession.objects.values_list("status", flat=True))
    seen = BatterySample.objects.aggregate(lowest=Min("charge"))["lowest"]
    at_end = Vehicle.objects.aggregate(lowest=Min("battery_charge"))["lowest"]
    return {
        "charge_sessions": dict(sessions),
        "battery_lowest_pct_seen": None if seen is None else round(seen, 1),
        "battery_lowest_pct_at_end": None if at_end is None else round(at_end, 1),
    }


def timed(seconds: float) -> float:
    """Sleep and return the time slept (the rows' pacing)."""
    time.sleep(seconds)
    return seconds
