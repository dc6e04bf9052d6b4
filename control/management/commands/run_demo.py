"""`manage.py run_demo`: the whole fleet with simulated vehicles, on embedded defaults.

Without REDIS_URL the web server and `control` share this process (the in-memory channel layer
cannot cross processes) and Celery runs eagerly; with REDIS_URL the Procfile's processes are
started as children. The MQTT broker is the embedded amqtt one unless MQTT_URL is set.
"""

import json
import signal
import sys
import tempfile
import threading
import time
from typing import Any

from django.conf import settings
from django.core.management import call_command
from django.core.management.base import BaseCommand, CommandParser

from control.demo import (
    DEMO_PASSWORD,
    DEMO_ROLE_USERS,
    DEMO_USER,
    Children,
    EmbeddedBeat,
    OrderStream,
    ensure_demo_data,
    wait_for_port,
)
from control.service import build_control_loop
from fleet.mqtt import BrokerAddress
from maps.selectors import layout_as_dict


class Command(BaseCommand):
    help = "Run the fleet manager with simulated vehicles and a continuous stream of orders."

    def add_arguments(self, parser: CommandParser) -> None:
        parser.add_argument("--host", default="127.0.0.1")
        parser.add_argument("--port", type=int, default=8000)
        parser.add_argument("--vehicles", type=int, default=4)
        parser.add_argument(
            "--time-scale",
            type=float,
            default=2.0,
            help="simulated time runs this many times faster",
        )
        parser.add_argument("--no-orders", action="store_true", help="no automatic orders")

    def handle(self, *args: Any, **options: Any) -> None:
        started = time.monotonic()
        call_command("migrate", interactive=False, verbosity=0)
        call_command("collectstatic", interactive=False, verbosity=0)
        layout = ensure_demo_data()
        children = Children()
        try:
            self._start_broker(children)
            self._start_simulator(children, layout_as_dict(map=layout), options)
            orders = OrderStream(layout, options["vehicles"])
            if not options["no_orders"]:
                orders.start()
            url = f"http://{options['host']}:{options['port']}/"
            self.stdout.write(
                self.style.SUCCESS(
                    f"Open Fleet demo: {url}  (login {DEMO_USER} / {DEMO_PASSWORD}), "
                    f"{options['vehicles']} vehicles, ready in {time.monotonic() - started:.1f} s"
                )
            )
            self.stdout.write(f"Role logins (password = name): {', '.join(DEMO_ROLE_USERS)}")
            sys.stdout.flush()
            if settings.REDIS_URL:
                self._run_production_topology(children, options)
            else:
                self._run_in_process(options)
        finally:
            children.stop()
            self.stdout.write("demo stopped")

    def _start_broker(self, children: Children) -> None:
        if not settings.MQTT_EMBEDDED:
            return
        address = BrokerAddress.from_url(settings.MQTT_URL)
        children.python(
            "broker", "-m", "fleet.broker", "--host", address.host, "--port", str(address.port)
        )
        wait_for_port(address.host, address.port)

    def _start_simulator(
        self, children: Children, layout: dict[str, Any], options: dict[str, Any]
    ) -> None:
        with tempfile.NamedTemporaryFile("w", suffix=".json", delete=False) as handle:
            json.dump(layout, handle)
        children.python(
            "simulator",
            "-m",
            "simulator",
            "--count",
            str(options["vehicles"]),
            "--layout",
            handle.name,
            "--broker",
            settings.MQTT_URL,
            "--interface",
            settings.VDA5050_INTERFACE,
            "--time-scale",
            str(options["time_scale"]),
            "--visualization-hz",
            "5",
            "--log-level",
            "WARNING",
        )

    def _run_in_process(self, options: dict[str, Any]) -> None:
        """Web server in the main thread, `control` in a thread of the same process."""
        from daphne.endpoints import build_endpoint_description_strings
        from daphne.server import Server

        from fleet.asgi import application

        control = build_control_loop()
        thread = threading.Thread(target=control.run, name="control", daemon=True)
        thread.start()
        from orders.tasks import PERIODIC

        periodic = {
            name: {"task": task, "schedule": every} for name, (every, task) in PERIODIC.items()
        }
        beat = EmbeddedBeat(settings.CELERY_BEAT_SCHEDULE | periodic)
        beat.start()
        server = Server(
            application=application,
            signal_handlers=True,
            endpoints=build_endpoint_description_strings(
                host=options["host"], port=options["port"]
            ),
        )
        try:
            server.run()  # returns on SIGINT/SIGTERM
        finally:
            beat.stopped.set()
            control.stop()
            thread.join(timeout=10)

    def _run_production_topology(self, children: Children, options: dict[str, Any]) -> None:
        """The Procfile's processes as children; returns when one dies or on SIGINT/SIGTERM."""
        children.start(
            "web",
            [
                sys.executable,
                "-m",
                "daphne",
                "-b",
                options["host"],
                "-p",
                str(options["port"]),
                "fleet.asgi:application",
            ],
        )
        children.python("control", "manage.py", "run_control")
        children.python(
            "worker",
            "-m",
            "celery",
            "-A",
            "fleet",
            "worker",
            "--concurrency",
            "2",
            "--loglevel",
            "WARNING",
        )
        children.python(
            "beat",
            "-m",
            "celery",
            "-A",
            "fleet",
            "beat",
            "--loglevel",
            "WARNING",
            "--schedule",
            f"{tempfile.gettempdir()}/fleet-celerybeat-schedule",
        )
        stop = threading.Event()
        for sig in (signal.SIGTERM, signal.SIGINT):
            signal.signal(sig, lambda *_: stop.set())
        while not stop.wait(1.0):
            if (dead := children.failed()) is not None:
                self.stderr.write(f"{dead} exited; stopping the demo")
                return
