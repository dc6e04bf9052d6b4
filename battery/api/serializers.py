"""Serializers of battery state (read only)."""

from typing import Any

from rest_framework import serializers

from battery.models import BatterySample, Charger, ChargeSession


class ChargerSerializer(serializers.ModelSerializer[Charger]):
    """A charger with its station, points and which of them are booked now."""

    station_id = serializers.CharField(source="station.station_id")
    map_id = serializers.CharField(source="station.map.map_id")
    vehicle_types: serializers.SlugRelatedField[Any] = serializers.SlugRelatedField(
        many=True, read_only=True, slug_field="type_id"
    )
    booked_points = serializers.SerializerMethodField()

    class Meta:
        model = Charger
        fields = [
            "id",
            "station_id",
            "map_id",
            "capacity",
            "is_active",
            "vehicle_types",
            "booked_points",
        ]
        read_only_fields = fields

    def get_booked_points(self, charger: Charger) -> list[dict[str, Any]]:
        booked = self.context.get("booked", {})
        return [
            {"point": point, "vehicle": vehicle}
            for (charger_id, point), vehicle in sorted(booked.items())
            if charger_id == charger.pk
        ]


class ChargeSessionSerializer(serializers.ModelSerializer[ChargeSession]):
    charger_station = serializers.CharField(source="charger.station.station_id", default=None)

    class Meta:
        model = ChargeSession
        fields = [
            "id",
            "vehicle",
            "charger",
            "charger_station",
            "point",
            "status",
            "reason",
            "route",
            "start_charge",
            "end_charge",
            "note",
            "created_at",
            "started_at",
            "ended_at",
        ]
        read_only_fields = fields


class VehicleEnergySerializer(serializers.Serializer[Any]):
    """A vehicle's battery: charge, band against its policy, learned model, cycles, health."""

    vehicle = serializers.IntegerField(source="pk")
    name = serializers.CharField(source="__str__")
    battery_charge = serializers.FloatField(allow_null=True)
    charging = serializers.BooleanField()
    band = serializers.CharField(allow_null=True)
    drain_per_metre = serializers.FloatField(allow_null=True)
    drain_per_hour = serializers.FloatField(allow_null=True)
    charge_cycles = serializers.FloatField()
    health = serializers.FloatField(allow_null=True)
    session = serializers.IntegerField(allow_null=True)
    session_status = serializers.CharField(allow_null=True)


class BatterySampleSerializer(serializers.ModelSerializer[BatterySample]):
    class Meta:
        model = BatterySample
        fields = ["at", "charge", "charging", "drain_per_metre"]
        read_only_fields = fields
