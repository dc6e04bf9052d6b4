"""Admin of what `control` records: each vehicle's maps and zone sets (read-only)."""

from typing import Any

from django.contrib import admin
from django.db.models import F, Q, QuerySet
from django.http import HttpRequest

from control.models import VehicleMap


class OutdatedFilter(admin.SimpleListFilter):
    """Vehicles whose enabled map version is not the released one."""

    title = "enabled version"
    parameter_name = "outdated"

    def lookups(self, request: HttpRequest, model_admin: Any) -> list[tuple[str, str]]:
        return [("yes", "not the released one"), ("no", "the released one")]

    def queryset(self, request: HttpRequest, queryset: QuerySet[Any]) -> QuerySet[Any]:
        differs = ~Q(enabled_version=F("released_version")) & ~Q(released_version="")
        if self.value() == "yes":
            return queryset.filter(differs)
        if self.value() == "no":
            return queryset.exclude(differs)
        return queryset


@admin.register(VehicleMap)
class VehicleMapAdmin(admin.ModelAdmin[VehicleMap]):
    list_display = [
        "vehicle",
        "map_id",
        "enabled_version",
        "released_version",
        "is_outdated",
        "status",
        "reason",
        "zone_set_status",
        "updated_at",
    ]
    list_filter = [OutdatedFilter, "status", "map_id", "zone_set_status"]
    search_fields = ["vehicle__serial_number", "map_id"]

    @admin.display(boolean=True, description="outdated")
    def is_outdated(self, obj: VehicleMap) -> bool:
        return obj.outdated

    def has_add_permission(self, request: HttpRequest) -> bool:
        return False  # written by control only

    def has_change_permission(self, request: HttpRequest, obj: Any = None) -> bool:
        return False
