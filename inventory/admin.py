"""Admin of load carriers, storage locations, movements and discrepancies."""

from django.contrib import admin

from inventory.models import Discrepancy, LoadCarrier, Movement, StorageLocation


@admin.register(StorageLocation)
class StorageLocationAdmin(admin.ModelAdmin[StorageLocation]):
    list_display = ["station", "capacity", "active", "note"]
    list_filter = ["active", "station__map"]
    search_fields = ["station__station_id", "note"]


@admin.register(LoadCarrier)
class LoadCarrierAdmin(admin.ModelAdmin[LoadCarrier]):
    list_display = ["load_id", "load_type", "location", "slot", "vehicle", "weight", "updated_at"]
    list_filter = ["load_type"]
    search_fields = ["load_id"]
    # Positions change through pick/drop, state and the services, which record movements.
    readonly_fields = ["location", "slot", "vehicle"]


@admin.register(Movement)
class MovementAdmin(admin.ModelAdmin[Movement]):
    list_display = [
        "at",
        "load",
        "reason",
        "from_location",
        "from_vehicle",
        "to_location",
        "to_vehicle",
        "order_ref",
    ]
    list_filter = ["reason"]
    search_fields = ["load__load_id", "order_ref"]
    readonly_fields = [f.name for f in Movement._meta.fields]


@admin.register(Discrepancy)
class DiscrepancyAdmin(admin.ModelAdmin[Discrepancy]):
    list_display = [
        "detected_at",
        "kind",
        "load_id",
        "vehicle",
        "location",
        "resolved_at",
        "message",
    ]
    list_filter = ["kind", "resolved_at"]
    search_fields = ["load_id", "key", "message"]
