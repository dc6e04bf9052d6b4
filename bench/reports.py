"""Report pages with 30 days of history for 100 vehicles: time per page and per CSV export.

Creates a throw-away database (Django's test database for DATABASE_URL, or --database-url; SQLite
if neither is set), writes generated history through the same ledger the Celery roll-up and
sampler use (`reports.history`), then requests the report page and exports over Django's test
client (full request: middleware, session, queries, template) and prints p50/p95/max. Target:
under 500 ms per page (issue 9).
"""

import argparse
import os
import statistics
import time
from datetime import timedelta
from typing import Any


def timed(get: Any, url: str, repeat: int) -> dict[str, float]:
    times = []
    for _ in range(repeat):
        began = time.perf_counter()
        response = get(url)
        times.append((time.perf_counter() - began) * 1000)
        assert response.status_code == 200, (url, response.status_code)
    times.sort()
    return {
        "p50_ms": round(statistics.median(times), 1),
        "p95_ms": round(times[int(0.95 * (len(times) - 1))], 1),
        "max_ms": round(times[-1], 1),
    }


def run(vehicles: int, days: int, repeat: int) -> dict[str, Any]:
    from django.contrib.auth import get_user_model
    from django.test import Client
    from django.utils import timezone

    from fleet.roles import MANAGER, assign_role
    from reports.history import generate_history
    from reports.models import (
        LeadTimeCount,
        VehicleHour,
        WaitDayCount,
        WaitHourCount,
        WaitNodeDay,
    )

    began = time.perf_counter()
    orders = generate_history(vehicles=vehicles, days=days)
    generate_s = time.perf_counter() - began
    client = Client()
    manager = get_user_model().objects.create_user("bench-manager")
    assign_role(user=manager, role=MANAGER)  # reports need fleet.view_reports
    client.force_login(manager)
    today = timezone.localdate()
    month = f"start={today - timedelta(days=days)}&end={today}"
    week = f"start={today - timedelta(days=6)}&end={today}"
    client.get(f"/reports/?{week}")  # warm up templates and connections
    return {
        "vehicles": vehicles,
        "days": days,
        "orders": orders,
        "hour_rows": VehicleHour.objects.count(),
        "lead_time_rows": LeadTimeCount.objects.count(),
        "generate_s": round(generate_s, 1),
        "page_30_days": timed(client.get, f"/reports/?{month}", repeat),
        "page_7_days": timed(client.get, f"/reports/?{week}", repeat),
        "page_30_days_one_vehicle": timed(client.get, f"/reports/?{month}&vehicles=1", repeat),
        "csv_throughput_30_days": timed(client.get, f"/reports/throughput.csv?{month}", repeat),
        "csv_utilisation_30_days": timed(client.get, f"/reports/utilisation.csv?{month}", repeat),
        "csv_waits_vehicles_30_days": timed(
            client.get, f"/reports/waits_vehicles.csv?{month}", repeat
        ),
        "wait_rows": WaitHourCount.objects.count()
        + WaitDayCount.objects.count()
        + WaitNodeDay.objects.count(),
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--vehicles", type=int, default=100)
    parser.add_argument("--days", type=int, default=30)
    parser.add_argument("--repeat", type=int, default=20)
    parser.add_argument("--database-url", help="database server to create the test database on")
    args = parser.parse_args()
    if args.database_url:
        os.environ["DATABASE_URL"] = args.database_url
    os.environ.setdefault("DJANGO_SETTINGS_MODULE", "fleet.settings")
    os.environ.setdefault("ALLOWED_HOSTS", "testserver")
    import django
    from django.db import connection
    from django.test.utils import setup_databases, setup_test_environment, teardown_databases

    django.setup()
    setup_test_environment()
    old = setup_databases(verbosity=0, interactive=False)
    try:
        figures = run(args.vehicles, args.days, args.repeat) | {"database": connection.vendor}
    finally:
        teardown_databases(old, verbosity=0)
    print(
        f"{figures['vehicles']} vehicles, {figures['days']} days on {figures['database']}: "
        f"{figures['orders']:,} orders, {figures['hour_rows']:,} hourly and "
        f"{figures['lead_time_rows']:,} lead-time and {figures['wait_rows']:,} traffic-wait rows "
        f"(written in {figures['generate_s']} s)"
    )
    for name in ("page_30_days", "page_7_days", "page_30_days_one_vehicle"):
        t = figures[name]
        print(
            f"{name}: p50 {t['p50_ms']} ms, p95 {t['p95_ms']} ms, max {t['max_ms']} ms (< 500 ms)"
        )
    for name in ("csv_throughput_30_days", "csv_utilisation_30_days", "csv_waits_vehicles_30_days"):
        t = figures[name]
        print(f"{name}: p50 {t['p50_ms']} ms, p95 {t['p95_ms']} ms")
    from bench import results

    print(f"wrote {results.write('reports', figures)}")


if __name__ == "__main__":
    main()
