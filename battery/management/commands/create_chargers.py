"""Create a charger (one point, every vehicle type) for each charge station that has none."""

from typing import Any

from django.core.management.base import BaseCommand

from battery.services import create_missing_chargers


class Command(BaseCommand):
    help = __doc__

    def handle(self, *args: Any, **options: Any) -> None:
        created = create_missing_chargers()
        self.stdout.write(f"{len(created)} charger(s) created: {', '.join(created) or '-'}")
