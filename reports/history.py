"""Generated report history (for demos and the report benchmark), written like the real one.

Orders go through `Ledger.add_order` exactly as the roll-up adds them; vehicle time is added per
hour as the sampler would have added it over that hour. Vehicles are created as `generated/GEN-NNN`.
"""

import random
from datetime import datetime, timedelta

from django.db import transaction
from django.utils import timezone

from maps.demo import warehouse_layout
from maps.models import Node
from maps.selectors import get_default_map
from maps.services import create_layout
from orders.models import TransportOrder
from reports.services import TIME_COLUMNS, EndedOrder, Ledger, day_of, hour_of
from reports.waits import WaitEpisode, WaitLedger
from robots.models import Vehicle
from robots.services import register_vehicles

ERROR_TYPES = ["bumperTriggered", "laserScannerBlocked", "batteryLow", "noRouteFound"]


def generate_history(
    *,
    vehicles: int,
    days: int,
    orders_per_hour: float = 6.0,
    waits_per_hour: float = 6.0,
    seed: int = 1,
    end: datetime | None = None,
) -> int:
    """Write `days` of history for `vehicles` vehicles ending at `end`; return the orders added.
    Traffic waits go to the first layout's crossings (the demo warehouse is created if there
    is no layout), each vehicle waiting around a few of them, busy ones more often."""
    rng = random.Random(seed)  # noqa: S311  (made-up figures, not secrets)
    end = hour_of(end or timezone.now())
    ids = register_vehicles(
        identities=[("generated", f"GEN-{n:03d}") for n in range(1, vehicles + 1)]
    )
    layout = get_default_map() or create_layout(spec=warehouse_layout(columns=8, rows=5))
    crossings = list(Node.objects.filter(map=layout).values_list("node_id", flat=True))
    ledger, waits, added = Ledger(), WaitLedger(), 0
    for vehicle_id in ids.values():
        beat = rng.sample(crossings, min(8, len(crossings)))
        hour = end - timedelta(days=days)
        while hour < end:
            added += _orders(ledger, rng, vehicle_id, hour, orders_per_hour)
            _time(ledger, rng, vehicle_id, hour)
            _waits(waits, rng, vehicle_id, hour, waits_per_hour, layout.map_id, beat)
            hour += timedelta(hours=1)
    with transaction.atomic():
        ledger.apply()
        waits.apply()
    Vehicle.objects.filter(pk__in=ids.values()).update(connection=Vehicle.Connection.OFFLINE)
    return added


def _orders(
    ledger: Ledger, rng: random.Random, vehicle_id: int, hour: datetime, rate: float
) -> int:
    count = max(0, round(rng.gauss(rate, rate / 3)))
    for _ in range(count):
        finished = hour + timedelta(seconds=rng.uniform(0, 3599))
        waiting, approach, execution = (rng.expovariate(1 / mean) for mean in (90, 120, 240))
        created = finished - timedelta(seconds=waiting + approach + execution)
        status = (
            TransportOrder.Status.FINISHED if rng.random() > 0.02 else TransportOrder.Status.FAILED
        )
        deadline = created + timedelta(minutes=15) if rng.random() < 0.5 else None
        ledger.add_order(
            EndedOrder(
                vehicle_id=vehicle_id,
                status=status,
                created_at=created,
                assigned_at=created + timedelta(seconds=waiting),
                started_at=created + timedelta(seconds=waiting + approach),
                finished_at=finished,
                deadline=deadline,
            )
        )
    return count


def _time(ledger: Ledger, rng: random.Random, vehicle_id: int, hour: datetime) -> None:
    weights = [
        rng.uniform(4, 8),
        rng.uniform(1, 3),
        rng.uniform(0, 1.5),
        rng.uniform(0, 0.2),
        rng.uniform(0, 0.3),
    ]
    row = ledger.hours[(hour, vehicle_id)]
    for column, weight in zip(TIME_COLUMNS, weights, strict=True):
        row[column] += 3600 * weight / sum(weights)
    row["distance_m"] += rng.uniform(800, 2400)
    row["energy_pct"] += rng.uniform(5, 12)
    if rng.random() < 0.03:
        ledger.errors[(day_of(hour), vehicle_id)][rng.choice(ERROR_TYPES)] += 1


def _waits(
    ledger: WaitLedger,
    rng: random.Random,
    vehicle_id: int,
    hour: datetime,
    rate: float,
    map_id: str,
    beat: list[str],
) -> None:
    if not beat:
        return
    busy = 1.6 if 7 <= timezone.localtime(hour).hour < 18 else 0.6  # the day shift is busier
    for _ in range(max(0, round(rng.gauss(rate * busy, rate / 3)))):
        # The first crossings of a vehicle's beat are its hot spots.
        node = beat[min(int(rng.expovariate(0.6)), len(beat) - 1)]
        started = hour + timedelta(seconds=rng.uniform(0, 3599))
        ledger.add(WaitEpisode(vehicle_id, map_id, node, started, rng.expovariate(1 / 12)))
