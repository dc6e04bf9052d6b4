"""`manage.py validate_layout MAP_ID`: list a layout's findings; exit status 1 on errors."""

from typing import Any

from django.core.management.base import BaseCommand, CommandError, CommandParser

from maps.models import Map
from maps.selectors import validate_layout


class Command(BaseCommand):
    help = "Validate a map: reachability, dead ends, stations, vehicle types, traffic layout."

    def add_arguments(self, parser: CommandParser) -> None:
        parser.add_argument("map_id")

    def handle(self, *args: Any, **options: Any) -> None:
        layout = Map.objects.filter(map_id=options["map_id"]).first()
        if layout is None:
            raise CommandError(f"no map {options['map_id']}")
        findings = validate_layout(map=layout)
        for finding in findings:
            self.stdout.write(str(finding))
        errors = sum(f.severity == "error" for f in findings)
        self.stdout.write(f"{layout.map_id}: {errors} error(s), {len(findings) - errors} other")
        if errors:
            raise CommandError(f"{errors} error(s) in map {layout.map_id}")
