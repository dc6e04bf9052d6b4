"""`manage.py run_control`: the master control process, as leader or standby."""

import gc
import signal
import sys
from typing import Any

from django.conf import settings
from django.core.management.base import BaseCommand
from django.db import connections

from control import broadcasts
from control.health import LeaderHeartbeat, start_health_server
from control.leader import Leadership, LeaseTimes, conninfo_from_settings
from control.service import build_control_loop
from control.standby import StandbyControl


class Command(BaseCommand):
    help = (
        "Run the master control: VDA 5050 in and out, live fleet model, order execution. "
        "Start two for a standby pair: one leads (PostgreSQL advisory lock), the other waits."
    )

    def handle(self, *args: Any, **options: Any) -> None:
        database = settings.DATABASES["default"]
        if database["ENGINE"] != "django.db.backends.sqlite3":
            # Read at each connect; the web keeps its own (0) under ASGI's thread pool.
            connections.settings["default"]["CONN_MAX_AGE"] = settings.CONTROL_DB_CONN_MAX_AGE
        leadership = None
        if database["ENGINE"] == "django.db.backends.postgresql":
            times = LeaseTimes.from_settings(settings.CONTROL_LEASE)
            leadership = Leadership(conninfo_from_settings(database), times)
        broadcasts.start()  # browser broadcasts leave without waiting on the main loop
        # Django, the apps and the layouts are loaded for good: keep the collector off them,
        # and collect the young generation less often (a state message allocates dozens of
        # objects; the default threshold ran a collection every few messages).
        gc.freeze()
        gc.set_threshold(settings.CONTROL_GC_THRESHOLD, 20, 20)
        # The paho thread waits for the GIL while the main loop plans or builds rows: a shorter
        # switch interval (default 5 ms) lets it take messages off the socket sooner.
        sys.setswitchinterval(settings.CONTROL_SWITCH_INTERVAL)
        control = StandbyControl(leadership, build_control_loop)
        health = start_health_server(settings.CONTROL_HEALTH_PORT, control.status)
        heartbeat = LeaderHeartbeat(control.status).start()
        signal.signal(signal.SIGTERM, lambda *_: control.stop())
        signal.signal(signal.SIGINT, lambda *_: control.stop())
        self.stdout.write(
            f"control: broker {settings.MQTT_URL}, interface {settings.VDA5050_INTERFACE}, "
            f"{'leader or standby' if leadership else 'single process'}, "
            f"health port {health.port if health else 'off'}"
        )
        try:
            control.run()  # returns after a clean shutdown
        finally:
            heartbeat.stop()
            if health is not None:
                health.stop()
