"""Writes of zones: create, change, delete, enable. Each marks the map's layout as changed."""

from collections.abc import Iterable
from typing import Any

from django.db import transaction

from fleet import audit
from fleet.exceptions import InvalidRequestError
from maps.geometry import Polygon
from maps.models import Map, VehicleType, Zone
from maps.services.layouts import mark_layout_changed
from maps.zoning import zone_problems

ZONE_FIELDS = (
    "zone_id",
    "zone_type",
    "vertices",
    "name",
    "description",
    "enabled",
    "max_speed",
    "direction",
    "limitation",
    "penalty_factor",
    "priority_factor",
    "release_loss_behavior",
    "entry_actions",
    "during_actions",
    "exit_actions",
)


class ZoneError(InvalidRequestError):
    """Zone data that breaks the rules of its type; `problems` maps fields to messages."""

    def __init__(self, problems: dict[str, list[str]]) -> None:
        self.problems = problems
        text = "; ".join(f"{field}: {', '.join(msgs)}" for field, msgs in problems.items())
        super().__init__(f"invalid zone: {text}")


def counter_clockwise(vertices: Iterable[dict[str, float]]) -> list[dict[str, float]]:
    """Zone vertices as stored: [{x, y}] counter-clockwise, repeated points dropped."""
    polygon = Polygon.of((v["x"], v["y"]) for v in vertices)
    return [{"x": x, "y": y} for x, y in polygon.vertices]


@transaction.atomic
def create_zone(*, map: Map, vehicle_types: Iterable[VehicleType] = (), **fields: Any) -> Zone:
    """Create a zone on `map` from model field values (`ZONE_FIELDS`; `zone_id`, `zone_type` and
    `vertices` required). Raises ZoneError when the data breaks the rules of its type."""
    unknown = set(fields) - set(ZONE_FIELDS)
    if unknown:
        raise InvalidRequestError(f"unknown zone fields: {', '.join(sorted(unknown))}")
    zone = Zone(map=map, **fields)
    _check(zone)
    if Zone.objects.filter(map=map, zone_id=zone.zone_id).exists():
        raise ZoneError({"zone_id": [f"map {map.map_id} has a zone {zone.zone_id} already"]})
    zone.vertices = counter_clockwise(zone.vertices)
    zone.save()
    zone.vehicle_types.set(vehicle_types)
    mark_layout_changed(maps=[map])
    audit.record(
        "zone.create", target_type="zone", target_id=zone.zone_id, detail={"map": map.map_id}
    )
    return zone


@transaction.atomic
def update_zone(
    *, zone: Zone, vehicle_types: Iterable[VehicleType] | None = None, **changes: Any
) -> Zone:
    """Change the given fields of `zone` (and its vehicle types, when given)."""
    unknown = set(changes) - set(ZONE_FIELDS)
    if unknown:
        raise InvalidRequestError(f"unknown zone fields: {', '.join(sorted(unknown))}")
    for name, value in changes.items():
        setattr(zone, name, value)
    _check(zone)
    duplicate = Zone.objects.filter(map_id=zone.map_id, zone_id=zone.zone_id).exclude(pk=zone.pk)
    if duplicate.exists():
        raise ZoneError({"zone_id": [f"the map has a zone {zone.zone_id} already"]})
    zone.vertices = counter_clockwise(zone.vertices)
    zone.save()
    if vehicle_types is not None:
        zone.vehicle_types.set(vehicle_types)
    mark_layout_changed(maps=[zone.map])
    audit.record(
        "zone.change",
        target_type="zone",
        target_id=zone.zone_id,
        detail={"fields": sorted(changes)},
    )
    return zone


@transaction.atomic
def delete_zone(*, zone: Zone) -> None:
    """Delete `zone`; routing forgets it."""
    layout, zone_id = zone.map, zone.zone_id
    zone.delete()
    mark_layout_changed(maps=[layout])
    audit.record(
        "zone.delete", target_type="zone", target_id=zone_id, detail={"map": layout.map_id}
    )


@transaction.atomic
def set_zones_enabled(*, zones: Iterable[Zone], enabled: bool) -> int:
    """Switch zones on or off (a closure for a shift, say); returns how many changed."""
    changed = [z for z in zones if z.enabled != enabled]
    for zone in changed:
        zone.enabled = enabled
    Zone.objects.bulk_update(changed, ["enabled"])
    mark_layout_changed(maps={z.map for z in changed})
    for zone in changed:
        audit.record(
            "zone.enable" if enabled else "zone.disable", target_type="zone", target_id=zone.zone_id
        )
    return len(changed)


def _check(zone: Zone) -> None:
    problems: dict[str, list[str]] = {}
    if not zone.zone_id or len(zone.zone_id) > 100:
        problems["zone_id"] = ["needs an id of 1 to 100 characters"]
    if zone.zone_type not in Zone.Type.values:
        problems["zone_type"] = [f"unknown zone type {zone.zone_type!r}"]
    for field, message in zone_problems(**zone.rule_fields()):
        problems.setdefault(field, []).append(message)
    if problems:
        raise ZoneError(problems)
