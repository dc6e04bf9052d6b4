"""`manage.py import_lif FILE [--site SITE] [--replace]`: import a LIF 1.0 layout file."""

from pathlib import Path
from typing import Any

from django.core.management.base import BaseCommand, CommandError, CommandParser

from maps.services import import_lif


class Command(BaseCommand):
    help = "Import a LIF 1.0 layout file into a site and print the report (no writes on errors)."

    def add_arguments(self, parser: CommandParser) -> None:
        parser.add_argument("file", type=Path)
        parser.add_argument("--site", default="default", help="site id (created if missing)")
        parser.add_argument(
            "--replace", action="store_true", help="replace an earlier import of the same project"
        )

    def handle(self, *args: Any, **options: Any) -> None:
        path: Path = options["file"]
        try:
            source = path.read_bytes()
        except OSError as exc:
            raise CommandError(f"cannot read {path}: {exc.strerror}") from None
        report = import_lif(
            source=source, site_id=options["site"], replace=options["replace"], file_name=path.name
        )
        for line in report.lines():
            self.stdout.write(line)
        if not report.ok:
            raise CommandError(f"{len(report.errors)} error(s): nothing imported")
