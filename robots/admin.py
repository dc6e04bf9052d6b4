"""Admin for the vehicle registry."""

from django.contrib import admin, messages
from django.db.models import QuerySet
from django.http import HttpRequest

from robots.models import MqttCredential, Vehicle
from robots.services import SNAPSHOT_FIELDS, issue_mqtt_password


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
    actions = ["issue_mqtt_login"]

    @admin.action(description="Issue a new MQTT login (shown once)")
    def issue_mqtt_login(self, request: HttpRequest, queryset: QuerySet[Vehicle]) -> None:
        for vehicle in queryset:
            try:
                username, password = issue_mqtt_password(vehicle=vehicle)
            except ValueError as error:
                self.message_user(request, f"{vehicle}: {error}", messages.ERROR)
                continue
            self.message_user(
                request,
                f"{vehicle}: user {username}, password {password} (copy it now: only its hash is "
                "kept; run `manage.py mosquitto_config` to update the broker)",
                messages.WARNING,
            )


@admin.register(MqttCredential)
class MqttCredentialAdmin(admin.ModelAdmin[MqttCredential]):
    list_display = ["username", "vehicle", "enabled", "issued_at"]
    list_filter = ["enabled"]
    search_fields = ["username", "vehicle__serial_number"]
    readonly_fields = ["vehicle", "username", "password_hash", "issued_at"]
