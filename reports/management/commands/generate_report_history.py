"""`manage.py generate_report_history`: fill the report tables with generated history."""

from typing import Any

from django.core.management.base import BaseCommand, CommandParser

from reports.history import generate_history


class Command(BaseCommand):
    help = "Write generated report history (vehicles generated/GEN-NNN) for demos and benchmarks."

    def add_arguments(self, parser: CommandParser) -> None:
        parser.add_argument("--vehicles", type=int, default=100)
        parser.add_argument("--days", type=int, default=30)
        parser.add_argument("--orders-per-hour", type=float, default=6.0, help="per vehicle")
        parser.add_argument("--seed", type=int, default=1)

    def handle(self, *args: Any, **options: Any) -> None:
        added = generate_history(
            vehicles=options["vehicles"],
            days=options["days"],
            orders_per_hour=options["orders_per_hour"],
            seed=options["seed"],
        )
        self.stdout.write(
            f"{added} orders over {options['days']} days for {options['vehicles']} vehicles"
        )
