"""Reads of zones: the rules routing applies, and zones as plain data."""

from collections import defaultdict
from typing import Any

from django.db.models import QuerySet

from maps.geometry import Polygon
from maps.models import Map, Zone
from maps.zoning import ZoneRule


def list_zones(*, map: Map, enabled: bool | None = None) -> QuerySet[Zone]:
    """The zones of `map` by id (all, or only the enabled or disabled ones)."""
    zones = Zone.objects.filter(map=map).prefetch_related("vehicle_types").order_by("zone_id")
    return zones if enabled is None else zones.filter(enabled=enabled)


def zone_rules(*, maps: QuerySet[Map]) -> list[ZoneRule]:
    """The enabled zones of `maps` as routing rules (a zone with broken vertices is skipped)."""
    types: dict[int, set[str]] = defaultdict(set)
    through = Zone.vehicle_types.through.objects.filter(zone__map__in=maps, zone__enabled=True)
    for zone_pk, type_id in through.values_list("zone_id", "vehicletype__type_id"):
        types[zone_pk].add(type_id)
    rules = []
    for zone in Zone.objects.filter(map__in=maps, enabled=True).select_related("map"):
        try:
            polygon = Polygon.of((v["x"], v["y"]) for v in zone.vertices)
        except (ValueError, KeyError, TypeError):
            continue  # validation reports it; routing must not fail on one bad zone
        rules.append(
            ZoneRule(
                zone_id=zone.zone_id,
                map_id=zone.map.map_id,
                zone_type=zone.zone_type,
                polygon=polygon,
                max_speed=zone.max_speed,
                direction=zone.direction,
                limitation=zone.limitation,
                penalty_factor=zone.penalty_factor,
                priority_factor=zone.priority_factor,
                vehicle_types=frozenset(types.get(zone.pk, ())),
            )
        )
    return rules


def zone_as_dict(zone: Zone) -> dict[str, Any]:
    """A zone as plain data for the layout editor and the API of the page (our field names)."""
    return {
        "id": zone.zone_id,
        "name": zone.name,
        "description": zone.description,
        "type": zone.zone_type,
        "enabled": zone.enabled,
        "vertices": [{"x": v["x"], "y": v["y"]} for v in zone.vertices],
        "maxSpeed": zone.max_speed,
        "direction": zone.direction,
        "limitation": zone.limitation,
        "penaltyFactor": zone.penalty_factor,
        "priorityFactor": zone.priority_factor,
        "releaseLossBehavior": zone.release_loss_behavior,
        "entryActions": zone.entry_actions,
        "duringActions": zone.during_actions,
        "exitActions": zone.exit_actions,
        "vehicleTypes": sorted(t.type_id for t in zone.vehicle_types.all()),
    }
