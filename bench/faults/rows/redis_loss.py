"""Redis loss (RELIABILITY.md §3 row 11): the row's redis-server (AOF everysec) is SIGKILLed
during orders and restarted after 2 s. Celery's queue, the channel layer and control's
command queue live there; the database stays the source of truth (beat's dispatch cycle and
control's 1 s order sync).

Figures: kills, orders lost, duplicate-content publishes, seconds from Redis up to the next
order assigned (dispatch resumed) p50/max.
"""

import signal
import time
from functools import partial
from typing import Any

from bench.faults.fleet import percentile, wait_until
from bench.faults.harness import Feeder, row_context, verdict, wait_all_closed, wait_online

VEHICLES = 3


def _assigned_events() -> int:
    from orders.models import OrderEvent

    return OrderEvent.objects.filter(kind=OrderEvent.Kind.ASSIGNED).count()


def _assigned_more(than: int) -> bool:
    return _assigned_events() > than


def run(*, full: bool, scale: float = 1.0) -> dict[str, Any]:
    with row_context(full=full) as context:
        fleet, redis = context.fleet, context.stack.redis
        orders = context.pick(max(4, int(24 * scale)), 150)
        kills = context.pick(max(1, int(3 * scale)), 10)
        fleet.control()
        fleet.worker(beat=True)
        fleet.simulator("simulator", count=VEHICLES)
        wait_online(context, VEHICLES)
        feeder = Feeder(context, orders, in_flight=VEHICLES + 2)
        feeder.start()
        resumed: list[float] = []
        for _ in range(kills):
            time.sleep(context.rng.uniform(3, 8))
            redis.signal(signal.SIGKILL)
            time.sleep(2)
            redis.start()
            up, assigned = time.monotonic(), _assigned_events()
            try:
                wait_until(
                    partial(_assigned_more, assigned),
                    120,
                    "dispatch after Redis",
                )
                resumed.append(time.monotonic() - up)
            except TimeoutError:
                pass
        feeder.join(timeout=orders * 5)
        feeder.stop()
        drained = wait_all_closed(context, feeder.ids, timeout=300)
        figures = verdict(context, feeder.ids)
        figures.update(
            {
                "redis_kills": kills,
                "dispatch_resumed_s_p50": percentile(resumed, 0.5),
                "dispatch_resumed_s_max": percentile(resumed, 1.0),
                "drained_s": drained,
                "feeder_errors": len(feeder.errors),
                "processes_alive": {n: p.alive() for n, p in fleet.processes.items()},
            }
        )
        figures["passed"] = bool(
            figures["nothing_lost"]
            and figures["all_finished"]
            and all(figures["processes_alive"].values())
        )
        return figures
