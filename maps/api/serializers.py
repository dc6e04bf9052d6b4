"""Serializers of layouts (read-only reference data) and of the LIF import input."""

from rest_framework import serializers

from maps.models import Map, Site, Station


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
        fields = ["id", "map_id", "name", "description", "site", "level", "revision", "updated_at"]


class SiteSerializer(serializers.ModelSerializer[Site]):
    maps = serializers.SlugRelatedField[Map](many=True, read_only=True, slug_field="map_id")

    class Meta:
        model = Site
        fields = ["id", "site_id", "name", "description", "maps"]


class LifImportInputSerializer(serializers.Serializer[None]):
    """Where an uploaded LIF file goes (query string or form fields)."""

    site = serializers.CharField(max_length=100, default="default")
    replace = serializers.BooleanField(default=False)
