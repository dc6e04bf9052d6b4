"""`manage.py create_demo_layout`: load the demo warehouse (aisles, stations, chargers, parking)."""

from typing import Any

from django.core.management.base import BaseCommand, CommandParser

from maps.demo import warehouse_layout
from maps.services import create_layout


class Command(BaseCommand):
    help = "Create the demo warehouse layout (aisles, pick/drop stations, chargers, parking)."

    def add_arguments(self, parser: CommandParser) -> None:
        parser.add_argument("--columns", type=int, default=8)
        parser.add_argument("--rows", type=int, default=5)
        parser.add_argument("--map-id", default="demo")
        parser.add_argument("--replace", action="store_true", help="replace an existing map")

    def handle(self, *args: Any, **options: Any) -> None:
        layout = create_layout(
            spec=warehouse_layout(
                columns=options["columns"], rows=options["rows"], map_id=options["map_id"]
            ),
            replace=options["replace"],
        )
        self.stdout.write(
            f"created map {layout.map_id}: {layout.nodes.count()} nodes, "
            f"{layout.edges.count()} edges, {layout.stations.count()} stations"
        )
