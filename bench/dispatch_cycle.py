"""Dispatch cycle at fleet scale: one whole `dispatch_pending_orders` through the ORM on PostgreSQL.

The load benchmark's warehouse (`bench.load.setup.layout_spec`: a park spur per vehicle, pick
stations on the top row, drop stations on the bottom), its vehicles online and idle on random
aisle nodes with the simulator's factsheet, a share of them busy with an active order, and
pending orders on random pick stations. Times two cycles: a backlog (`--orders` pending, e.g.
after a burst) and the steady state of issue 11 (one new order per second: one pending order).
Counts the SQL queries of each cycle (a per-vehicle query would show as ~vehicles queries) and,
with `--profile`, prints where the time goes. Steady-state cycles (which check only the
shortlist of vehicles nearest to the order, `orders.services.dispatch_shortlist`) alternate
with cycles over the whole fleet (as before the shortlist) and cycles that also decode every
vehicle's factsheet (as before `orders.services.dispatch_factsheets`). Last, control's side of
an assignment: the full re-read of every active order (what `order.assigned` cost before) and
the read of the one order the command names (`DjangoStore.assigned_orders`).

    DATABASE_URL=postgres://postgres@127.0.0.1:5432/fleet_bench python -m bench.dispatch_cycle

The database is created when missing and emptied of this benchmark's rows first; never point it
at a database whose data you need (it deletes all transport orders and vehicles).
"""

import argparse
import cProfile
import io
import json
import os
import pstats
import random
import statistics
import time
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any
from unittest import mock
from urllib.parse import urlsplit

from bench import results

BUSY_SHARE = 0.115  # vehicles executing in the 1,000-vehicle load benchmark (115 of 1,000)


def ensure_database(url: str) -> None:
    """Create the PostgreSQL database of `url` if it does not exist."""
    import psycopg

    name = urlsplit(url).path.lstrip("/")
    admin = url.rsplit("/", 1)[0] + "/postgres"
    with psycopg.connect(admin, autocommit=True) as conn:
        if not conn.execute("SELECT 1 FROM pg_database WHERE datname = %s", (name,)).fetchone():
            conn.execute(f'CREATE DATABASE "{name}"')


def factsheet(serial: str) -> dict[str, Any]:
    """The simulator's factsheet, as control stores it."""
    import msgspec

    from simulator.factsheet import build_factsheet

    message = build_factsheet(
        header_id=1,
        timestamp="2026-01-01T00:00:00Z",
        version="2.1.0",
        manufacturer="bench",
        serial_number=serial,
        speed_max=1.5,
        state_interval=0.5,
        visualization_hz=1.0,
        with_vehicle_config=True,
    )
    return msgspec.to_builtins(message)  # type: ignore[no-any-return]


def prepare(vehicles: int, seed: int) -> Any:
    """Fresh layout and fleet; returns the layout."""
    from bench.load.setup import layout_spec
    from maps.services import create_layout
    from orders.models import OrderEvent, TransportOrder
    from robots.models import Vehicle

    OrderEvent.objects.all().delete()
    TransportOrder.objects.all().delete()
    Vehicle.objects.all().delete()
    layout = create_layout(spec=layout_spec(vehicles), replace=True)
    aisles = list(layout.nodes.filter(node_id__startswith="A").values_list("node_id", flat=True))
    rng = random.Random(seed)
    sheet = factsheet("V")
    Vehicle.objects.bulk_create(
        Vehicle(
            manufacturer="bench",
            serial_number=f"V{n:04d}",
            connection="ONLINE",
            operating_mode="AUTOMATIC",
            map_id=layout.map_id,
            last_node_id=rng.choice(aisles),
            battery_charge=rng.uniform(40, 100),
            factsheet=sheet | {"serialNumber": f"V{n:04d}"},
        )
        for n in range(vehicles)
    )
    return layout


def add_orders(layout: Any, count: int, rng: random.Random, **fields: Any) -> None:
    from orders.models import TransportOrder

    picks = list(layout.stations.filter(kind="PICK"))
    drops = list(layout.stations.filter(kind="DROP"))
    TransportOrder.objects.bulk_create(
        TransportOrder(source=rng.choice(picks), destination=rng.choice(drops), **fields)
        for _ in range(count)
    )


def make_busy(share: float, rng: random.Random, layout: Any) -> int:
    """Give a share of the vehicles an active (IN_PROGRESS) order with its route and two steps,
    as in the load benchmark (control reads them all on a full sync)."""
    from orders.models import OrderStep, TransportOrder
    from robots.models import Vehicle

    vehicles = list(Vehicle.objects.order_by("pk"))
    busy = rng.sample(vehicles, int(len(vehicles) * share))
    picks = list(layout.stations.filter(kind="PICK").select_related("node"))
    drops = list(layout.stations.filter(kind="DROP").select_related("node"))
    orders = TransportOrder.objects.bulk_create(
        TransportOrder(
            source=(pick := rng.choice(picks)),
            destination=(drop := rng.choice(drops)),
            status=TransportOrder.Status.IN_PROGRESS,
            vehicle=vehicle,
            route=[vehicle.last_node_id, pick.node.node_id, drop.node.node_id],
            route_steps=[1, 2],
            vda_order_id=f"BUSY-{vehicle.pk}",
        )
        for vehicle in busy
    )
    OrderStep.objects.bulk_create(
        OrderStep(order=order, index=index, station=station, operation=operation)
        for order in orders
        for index, (station, operation) in enumerate(
            [(order.source, OrderStep.Operation.PICK), (order.destination, "DROP")]
        )
    )
    return len(busy)


@contextmanager
def whole_fleet() -> Iterator[None]:
    """Dispatch as before `orders.services.dispatch_shortlist`: every idle vehicle checked."""
    from orders.services import dispatch_shortlist

    with mock.patch.object(dispatch_shortlist, "MAX_ORDERS", 0):
        yield


@contextmanager
def decoding_every_factsheet() -> Iterator[None]:
    """Dispatch as before `orders.services.dispatch_factsheets`: the fleet read with every
    factsheet, decoded each cycle."""
    from orders import selectors
    from orders.services import dispatch

    read = selectors.get_dispatch_fleet

    def full(**kwargs: Any) -> Any:
        return read(**kwargs | {"with_factsheets": True})

    with (
        whole_fleet(),
        mock.patch.object(selectors, "get_dispatch_fleet", full),
        mock.patch.object(dispatch, "attach_factsheets", return_value=None),
    ):
        yield


def cycle(profile: bool) -> dict[str, Any]:
    """One dispatch cycle: milliseconds, queries, assigned orders (and a profile if asked)."""
    from django.db import connection
    from django.test.utils import CaptureQueriesContext

    from orders.services import dispatch

    profiler = cProfile.Profile() if profile else None
    with CaptureQueriesContext(connection) as queries:
        started = time.perf_counter()
        if profiler:
            profiler.enable()
        assigned = dispatch.dispatch_pending_orders()
        if profiler:
            profiler.disable()
        elapsed = (time.perf_counter() - started) * 1000
    row: dict[str, Any] = {
        "ms": round(elapsed, 1),
        "queries": len(queries.captured_queries),
        "assigned": len(assigned),
        "orders": [o.pk for o in assigned],
    }
    if profiler:
        out = io.StringIO()
        pstats.Stats(profiler, stream=out).sort_stats("cumulative").print_stats(30)
        row["profile"] = out.getvalue()
    return row


def control_reads(assigned: list[int], repeats: int) -> dict[str, float]:
    """Milliseconds (median) of control's two reads after an assignment: every active order
    (the full sync) and only the orders the `order.assigned` command names."""
    from django.conf import settings
    from django.db import connections

    from control.persistence import DjangoStore

    # As run_control: the connection is kept, not opened again by each read.
    connections.settings["default"]["CONN_MAX_AGE"] = settings.CONTROL_DB_CONN_MAX_AGE
    connections["default"].close()
    store = DjangoStore()
    full: list[float] = []
    named: list[float] = []
    for _ in range(repeats):  # alternating, as the cycles
        started = time.perf_counter()
        count = len(store.active_orders())
        full.append((time.perf_counter() - started) * 1000)
        started = time.perf_counter()
        store.assigned_orders(orders=assigned[-1:], charge_sessions=[], moves=[])
        named.append((time.perf_counter() - started) * 1000)
    return {
        "control_active_orders": count,
        "control_full_read_ms_median": round(statistics.median(full), 1),
        "control_named_read_ms_median": round(statistics.median(named), 1),
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--vehicles", type=int, default=1000)
    parser.add_argument("--orders", type=int, default=100, help="pending orders of the backlog")
    parser.add_argument("--repeats", type=int, default=5, help="steady-state cycles timed")
    parser.add_argument("--seed", type=int, default=5050)
    parser.add_argument("--profile", action="store_true", help="print a profile of each kind")
    parser.add_argument("--json", type=Path, help="write the figures here, not bench/results")
    args = parser.parse_args()
    url = os.environ.get("DATABASE_URL", "")
    if not url.startswith("postgres"):
        parser.error("set DATABASE_URL to a throw-away PostgreSQL database")
    ensure_database(url)
    os.environ["REDIS_URL"] = ""  # in-process stand-ins: nothing leaves this process
    os.environ.setdefault("DJANGO_SETTINGS_MODULE", "fleet.settings")
    import django

    django.setup()
    from django.conf import settings
    from django.core.management import call_command

    settings.DEBUG = False
    call_command("migrate", verbosity=0)
    rng = random.Random(args.seed)
    layout = prepare(args.vehicles, args.seed)
    busy = make_busy(BUSY_SHARE, rng, layout)
    figures: dict[str, Any] = {"vehicles": args.vehicles, "busy": busy, "orders": args.orders}

    add_orders(layout, 1, rng)  # warm-up: imports, connection, the routing graph's caches
    first = cycle(profile=False)  # and, in a worker, its first cycle decodes every factsheet
    figures |= {"first_cycle_ms": first["ms"], "first_cycle_queries": first["queries"]}
    print(f"first cycle of a process: {first['ms']:.0f} ms, {first['queries']} queries")
    add_orders(layout, args.orders, rng)
    backlog = cycle(args.profile)
    figures |= {f"backlog_{k}": v for k, v in backlog.items() if k not in {"profile", "orders"}}
    print(
        f"backlog: {args.orders} pending, {args.vehicles} vehicles ({busy} busy): "
        f"{backlog['ms']:.0f} ms, {backlog['queries']} queries, {backlog['assigned']} assigned"
    )
    if args.profile:
        print(backlog["profile"])

    steady: list[dict[str, Any]] = []
    whole: list[dict[str, Any]] = []  # as before the shortlist: every idle vehicle checked
    decoding: list[dict[str, Any]] = []  # as before the cache: every factsheet decoded
    assigned: list[int] = []
    for _ in range(args.repeats):  # alternating, so all see the same load of the machine
        add_orders(layout, 1, rng)
        steady.append(cycle(args.profile and not steady))
        assigned += steady[-1]["orders"]
        add_orders(layout, 1, rng)
        with whole_fleet():
            whole.append(cycle(profile=False))
        add_orders(layout, 1, rng)
        with decoding_every_factsheet():
            decoding.append(cycle(profile=False))
    series = (("steady", steady), ("steady_whole_fleet", whole), ("steady_decoding_all", decoding))
    for name, rows in series:
        figures[f"{name}_ms_median"] = round(statistics.median(r["ms"] for r in rows), 1)
        figures[f"{name}_ms_max"] = max(r["ms"] for r in rows)
        figures[f"{name}_queries"] = rows[0]["queries"]
        print(
            f"{name}: 1 pending: median {figures[f'{name}_ms_median']:.0f} ms, "
            f"max {figures[f'{name}_ms_max']:.0f} ms, {figures[f'{name}_queries']} queries"
        )
    if args.profile:
        print(steady[0]["profile"])
    reads = control_reads(assigned, args.repeats)
    figures |= reads
    print(
        f"control after an assignment, {reads['control_active_orders']} active orders: full "
        f"re-read {reads['control_full_read_ms_median']:.1f} ms, the named order "
        f"{reads['control_named_read_ms_median']:.1f} ms (median)"
    )
    if args.json:
        args.json.write_text(json.dumps(figures, indent=2, sort_keys=True) + "\n")
        print(f"wrote {args.json}")
    else:
        print(f"wrote {results.write('dispatch_cycle', figures)}")


if __name__ == "__main__":
    main()
