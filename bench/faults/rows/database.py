"""PostgreSQL restart under API load (RELIABILITY.md §3 row 2): `pg_ctl stop -m immediate`
while ERP clients post orders over HTTP (retrying the same Idempotency-Key on 503 or a lost
connection, as an ERP does), start again after 5 / 30 s.

Figures: requests by status, HTTP 500s (must be 0: the API answers 503 + Retry-After),
acknowledged (2xx) orders lost, half-written orders (no CREATED event or no steps), seconds
from PostgreSQL up to the first good write through the API and to control's next flush
(ingest reconnected), processes alive.
"""

import threading
import time
from collections import Counter
from datetime import UTC, datetime
from functools import partial
from typing import Any

from bench.faults.api import Api, issue_token
from bench.faults.fleet import percentile, wait_until
from bench.faults.harness import row_context, wait_online


class Load(threading.Thread):
    """One ERP client posting orders one after the other, each retried until acknowledged."""

    def __init__(self, api: Api, name: str) -> None:
        super().__init__(daemon=True)
        self.api, self.name_ = api, name
        self.halt = threading.Event()
        self.statuses: Counter[int] = Counter()
        self.acked: dict[str, int] = {}
        self.good_at: list[float] = []
        self.retry_after_missing = 0

    def run(self) -> None:
        n = 0
        while not self.halt.is_set():
            n += 1
            key = f"{self.name_}-{n}"
            deadline = time.monotonic() + 120
            while not self.halt.is_set() and time.monotonic() < deadline:
                status, body, headers = self.api.create_order(key, "PICK-1", "DROP-1", key)
                self.statuses[status] += 1
                if status in (200, 201):
                    self.acked[key] = int(body["id"])
                    self.good_at.append(time.monotonic())
                    break
                if status == 503 and "Retry-After" not in headers:
                    self.retry_after_missing += 1
                time.sleep(0.5)
            time.sleep(0.1)


def _last_flush() -> datetime | None:
    from django.db.models import Max

    from robots.models import Vehicle

    at: datetime | None = Vehicle.objects.aggregate(at=Max("last_seen"))["at"]
    return at


def _flushed_after(moment: datetime) -> bool:
    return (_last_flush() or moment) > moment


def _good_write_after(loads: list[Load], moment: float) -> bool:
    return any(t > moment for load in loads for t in load.good_at)


def run(*, full: bool, scale: float = 1.0) -> dict[str, Any]:
    from django.db import close_old_connections

    with row_context(full=full) as context:
        fleet, postgres = context.fleet, context.stack.postgres
        restarts = context.pick(max(1, int(2 * scale)), 5)
        downs = [5.0, 30.0] if full else [5.0]
        fleet.control()
        fleet.worker(beat=True)
        fleet.simulator("simulator", count=2)
        fleet.web()
        wait_online(context, 2)
        api = Api(fleet.web_port, issue_token("erp-faults"))
        loads = [Load(api, f"erp{n}") for n in range(3)]
        for load in loads:
            load.start()
        time.sleep(5)
        first_good: list[float] = []
        ingest: list[float] = []
        for restart in range(restarts):
            postgres.stop_immediate()
            time.sleep(downs[restart % len(downs)])
            postgres.start()
            up, up_wall = time.monotonic(), datetime.now(UTC)
            wait_until(
                partial(_good_write_after, loads, up),
                120,
                "a good write",
            )
            first_good.append(min(t for load in loads for t in load.good_at if t > up) - up)
            close_old_connections()
            ingest.append(
                wait_until(
                    partial(_flushed_after, up_wall),
                    120,
                    "control flushed again",
                )
            )
            time.sleep(5)
        for load in loads:
            load.halt.set()
        for load in loads:
            load.join(60)
        from orders.models import TransportOrder

        close_old_connections()
        acked = {key: pk for load in loads for key, pk in load.acked.items()}
        stored = dict(
            TransportOrder.objects.filter(pk__in=acked.values()).values_list("external_ref", "pk")
        )
        lost = [key for key, pk in acked.items() if stored.get(key) != pk]
        half = (
            TransportOrder.objects.filter(events__isnull=True).count()
            + TransportOrder.objects.filter(steps__isnull=True).count()
        )
        statuses: Counter[int] = Counter()
        for load in loads:
            statuses.update(load.statuses)
        figures: dict[str, Any] = {
            "restarts": restarts,
            "down_s": downs,
            "requests_by_status": {str(k): v for k, v in sorted(statuses.items())},
            "http_500s": sum(v for k, v in statuses.items() if k >= 500 and k != 503),
            "http_503s": statuses.get(503, 0),
            "retry_after_missing": sum(load.retry_after_missing for load in loads),
            "acknowledged_orders": len(acked),
            "acknowledged_lost": len(lost),
            "half_written_orders": half,
            "orders_in_db": TransportOrder.objects.count(),
            "first_good_write_s": [round(s, 2) for s in first_good],
            "first_good_write_s_max": percentile(first_good, 1.0),
            "ingest_reconnect_s": [round(s, 2) for s in ingest],
            "processes_alive": {n: p.alive() for n, p in fleet.processes.items()},
        }
        figures["passed"] = bool(
            figures["http_500s"] == 0
            and not lost
            and half == 0
            and figures["retry_after_missing"] == 0
            and all(figures["processes_alive"].values())
            and max(ingest, default=0) <= 10
        )
        return figures
