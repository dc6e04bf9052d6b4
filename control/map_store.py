"""The database side of map distribution and zone sets: releases and zones in, statuses out."""

import os
from typing import Any

from django.db import close_old_connections
from django.urls import reverse

from control.map_sync import MapStatus, MapTarget
from control.models import VehicleMap
from control.zone_sets import build_zone_set
from maps.models import Map
from maps.selectors import current_releases, list_zones, zone_as_dict
from vda5050 import v3

DEFAULT_PUBLIC_URL = "http://127.0.0.1:8000"


def public_url() -> str:
    """Where vehicles reach the web server (`FLEET_PUBLIC_URL`): the base of download links."""
    return os.environ.get("FLEET_PUBLIC_URL", DEFAULT_PUBLIC_URL).rstrip("/")


def load_targets() -> tuple[dict[str, MapTarget], dict[str, v3.ZoneSetDefinition]]:
    """The distributed releases (with their download links) and every map's zone set."""
    close_old_connections()
    base = public_url()
    targets = {
        map_id: MapTarget(
            map_id=map_id,
            version=release.version,
            link=base + reverse("maps:release-file", args=[release.token, release.file_name]),
            checksum=release.checksum,
        )
        for map_id, release in current_releases().items()
    }
    zone_sets = {
        layout.map_id: build_zone_set(
            layout.map_id, [zone_as_dict(z) for z in list_zones(map=layout, enabled=True)]
        )
        for layout in Map.objects.filter(zones__enabled=True).distinct()
    }
    return targets, zone_sets


def save_map_statuses(rows: list[tuple[int, MapStatus, str, str]]) -> None:
    """Upsert the vehicles' map statuses (`control.models.VehicleMap`)."""
    if not rows:
        return
    close_old_connections()
    for vehicle_pk, status, zone_set_id, zone_set_status in rows:
        values: dict[str, Any] = status.row() | {
            "zone_set_id": zone_set_id,
            "zone_set_status": zone_set_status,
        }
        VehicleMap.objects.update_or_create(
            vehicle_id=vehicle_pk, map_id=status.map_id, defaults=values
        )
