"""Serializers of vehicles."""

from rest_framework import serializers

from robots.models import Vehicle


class VehicleSerializer(serializers.ModelSerializer[Vehicle]):
    class Meta:
        model = Vehicle
        fields = [
            "id",
            "manufacturer",
            "serial_number",
            "name",
            "protocol_version",
            "connection",
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
