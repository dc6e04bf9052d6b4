"""`manage.py export_lif MAP_ID` or `export_lif --site SITE_ID`: write a layout as LIF 1.0."""

import json
from pathlib import Path
from typing import Any

from django.core.management.base import BaseCommand, CommandError, CommandParser

from maps.models import Map, Site
from maps.selectors import export_map_lif, export_site_lif


class Command(BaseCommand):
    help = "Export a map (or with --site, every map of a site) as a LIF 1.0 file."

    def add_arguments(self, parser: CommandParser) -> None:
        parser.add_argument("map_id", nargs="?", help="the map's mapId")
        parser.add_argument("--site", help="export every map of this site instead")
        parser.add_argument("-o", "--output", type=Path, help="file to write (default: stdout)")

    def handle(self, *args: Any, **options: Any) -> None:
        if options["site"]:
            site = Site.objects.filter(site_id=options["site"]).first()
            if site is None:
                raise CommandError(f"no site {options['site']}")
            document = export_site_lif(site=site)
        elif options["map_id"]:
            layout = Map.objects.filter(map_id=options["map_id"]).first()
            if layout is None:
                raise CommandError(f"no map {options['map_id']}")
            document = export_map_lif(map=layout)
        else:
            raise CommandError("name a MAP_ID or --site SITE_ID")
        text = json.dumps(document, indent=2, ensure_ascii=False) + "\n"
        if options["output"]:
            options["output"].write_text(text, encoding="utf-8")
            self.stderr.write(f"wrote {options['output']}")
        else:
            self.stdout.write(text, ending="")
