"""Admin for the vehicle registry."""

from django.contrib import admin

from robots.models import Vehicle
from robots.services import SNAPSHOT_FIELDS


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
    readonly_fields = [*SNAPSHOT_FIELDS, "factsheet", "created_at", "updated_at"]
