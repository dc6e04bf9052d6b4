"""`manage.py run_control`: the master control process."""

import signal
from typing import Any

from django.conf import settings
from django.core.management.base import BaseCommand

from control.service import build_control_loop


class Command(BaseCommand):
    help = "Run the master control: VDA 5050 in and out, live fleet model, order execution."

    def handle(self, *args: Any, **options: Any) -> None:
        loop = build_control_loop()
        signal.signal(signal.SIGTERM, lambda *_: loop.stop())
        signal.signal(signal.SIGINT, lambda *_: loop.stop())
        self.stdout.write(
            f"control: broker {settings.MQTT_URL}, interface {settings.VDA5050_INTERFACE}"
        )
        loop.run()  # returns after a clean shutdown
