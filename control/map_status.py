"""Reads of the vehicles' map distribution (`control.models.VehicleMap`)."""

from django.db.models import F, Q, QuerySet

from control.models import VehicleMap


def list_vehicle_maps(*, map_id: str | None = None) -> QuerySet[VehicleMap]:
    """Every vehicle × map `control` reported, by vehicle."""
    rows = VehicleMap.objects.select_related("vehicle")
    return rows if map_id is None else rows.filter(map_id=map_id)


def outdated_vehicle_maps(*, map_id: str | None = None) -> QuerySet[VehicleMap]:
    """Vehicles whose enabled version of a map is not its released one (REFERENCE K.47)."""
    return (
        list_vehicle_maps(map_id=map_id)
        .exclude(released_version="")
        .filter(~Q(enabled_version=F("released_version")))
    )
