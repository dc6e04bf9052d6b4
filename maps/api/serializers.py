"""Serializers of layouts (read-only reference data), zones, and the LIF import input."""

from typing import Any

from rest_framework import serializers

from maps.models import Map, Site, Station, VehicleType, Zone
from maps.zoning import ZONE_RULE_FIELDS, zone_problems


class StationSerializer(serializers.ModelSerializer[Station]):
    map = serializers.CharField(source="map.map_id", read_only=True)
    node = serializers.CharField(source="node.node_id", read_only=True)

    class Meta:
        model = Station
        fields = ["id", "station_id", "name", "kind", "map", "node"]


class MapSerializer(serializers.ModelSerializer[Map]):
    site = serializers.CharField(source="site.site_id", read_only=True, default=None)

    class Meta:
        model = Map
        fields = [
            "id",
            "map_id",
            "name",
            "description",
            "site",
            "level",
            "revision",
            "version",
            "updated_at",
        ]


class SiteSerializer(serializers.ModelSerializer[Site]):
    maps = serializers.SlugRelatedField[Map](many=True, read_only=True, slug_field="map_id")

    class Meta:
        model = Site
        fields = ["id", "site_id", "name", "description", "maps"]


class LifImportInputSerializer(serializers.Serializer[None]):
    """Where an uploaded LIF file goes (query string or form fields)."""

    site = serializers.CharField(max_length=100, default="default")
    replace = serializers.BooleanField(default=False)


class ZoneSerializer(serializers.ModelSerializer[Zone]):
    """A zone as the API shows it; `vertices` are [{x, y}] in metres, counter-clockwise."""

    map = serializers.CharField(source="map.map_id", read_only=True)
    vehicle_types = serializers.SlugRelatedField[VehicleType](
        many=True, read_only=True, slug_field="type_id"
    )

    class Meta:
        model = Zone
        fields = [
            "id",
            "zone_id",
            "map",
            "zone_type",
            "name",
            "description",
            "enabled",
            "vertices",
            "max_speed",
            "direction",
            "limitation",
            "penalty_factor",
            "priority_factor",
            "release_loss_behavior",
            "entry_actions",
            "during_actions",
            "exit_actions",
            "vehicle_types",
            "updated_at",
        ]


class ZoneInputSerializer(serializers.Serializer[Zone]):
    """What a client sends to create (all required fields) or change (any of them) a zone."""

    map = serializers.SlugRelatedField[Map](slug_field="map_id", queryset=Map.objects.all())
    zone_id = serializers.CharField(max_length=100)
    zone_type = serializers.ChoiceField(choices=Zone.Type.choices)
    vertices = serializers.ListField(child=serializers.DictField(), min_length=3)
    name = serializers.CharField(max_length=200, required=False, allow_blank=True)
    description = serializers.CharField(required=False, allow_blank=True)
    enabled = serializers.BooleanField(required=False)
    max_speed = serializers.FloatField(required=False, allow_null=True, min_value=0.0)
    direction = serializers.FloatField(required=False, allow_null=True)
    limitation = serializers.ChoiceField(
        choices=Zone.Limitation.choices, required=False, allow_blank=True
    )
    penalty_factor = serializers.FloatField(
        required=False, allow_null=True, min_value=0.0, max_value=1.0
    )
    priority_factor = serializers.FloatField(
        required=False, allow_null=True, min_value=0.0, max_value=1.0
    )
    release_loss_behavior = serializers.ChoiceField(
        choices=Zone.ReleaseLoss.choices, required=False, allow_blank=True
    )
    entry_actions = serializers.ListField(child=serializers.DictField(), required=False)
    during_actions = serializers.ListField(child=serializers.DictField(), required=False)
    exit_actions = serializers.ListField(child=serializers.DictField(), required=False)
    vehicle_types = serializers.SlugRelatedField[VehicleType](
        many=True, slug_field="type_id", queryset=VehicleType.objects.all(), required=False
    )

    def validate(self, attrs: dict[str, Any]) -> dict[str, Any]:
        """The rules of the zone's type, on the zone as it would be after this change."""
        merged = self.instance.rule_fields() if self.instance else {}
        merged.update({k: v for k, v in attrs.items() if k in ZONE_RULE_FIELDS})
        merged = {k: ("" if v is None and k in TEXT_FIELDS else v) for k, v in merged.items()}
        errors: dict[str, list[str]] = {}
        for field, message in zone_problems(**merged):
            errors.setdefault(field, []).append(message)
        if errors:
            raise serializers.ValidationError(errors)
        return attrs


TEXT_FIELDS = ("limitation", "release_loss_behavior")
