"""Admin for the vehicle registry."""

from django.contrib import admin

from robots.models import Vehicle


@admin.register(Vehicle)
class VehicleAdmin(admin.ModelAdmin[Vehicle]):
    list_display = [
        "__str__",
        "serial_number",
        "manufacturer",
        "connection",
        "operating_mode",
        "battery_charge",
        "last_node_id",
        "order_id",
        "last_seen",
    ]
    list_filter = ["connection", "manufacturer", "protocol_version", "operating_mode"]
    search_fields = ["serial_number", "name", "manufacturer"]
    readonly_fields = [
        "connection",
        "factsheet",
        "map_id",
        "x",
        "y",
        "theta",
        "position_initialized",
        "battery_charge",
        "charging",
        "driving",
        "paused",
        "operating_mode",
        "errors",
        "loads",
        "order_id",
        "order_update_id",
        "last_node_id",
        "last_node_sequence_id",
        "last_seen",
        "created_at",
        "updated_at",
    ]
