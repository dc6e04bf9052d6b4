"""Serializers of vehicles."""

from rest_framework import serializers

from robots.models import Vehicle


class VehicleSerializer(serializers.ModelSerializer[Vehicle]):
    """A vehicle's identity and latest state; `available` says whether dispatch may use it."""

    available = serializers.BooleanField(source="is_available", read_only=True)

    class Meta:
        model = Vehicle
        fields = [
            "id",
            "manufacturer",
            "serial_number",
            "name",
            "protocol_version",
            "connection",
            "available",
            "map_id",
            "x",
            "y",
            "theta",
            "battery_charge",
            "charging",
            "driving",
            "paused",
            "operating_mode",
            "errors",
            "loads",
            "order_id",
            "last_node_id",
            "last_seen",
        ]
        read_only_fields = fields
