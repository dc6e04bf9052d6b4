"""Serializers of layouts (read-only reference data)."""

from rest_framework import serializers

from maps.models import Map, Station


class StationSerializer(serializers.ModelSerializer[Station]):
    map = serializers.CharField(source="map.map_id", read_only=True)
    node = serializers.CharField(source="node.node_id", read_only=True)

    class Meta:
        model = Station
        fields = ["id", "station_id", "name", "kind", "map", "node"]


class MapSerializer(serializers.ModelSerializer[Map]):
    class Meta:
        model = Map
        fields = ["id", "map_id", "name", "description", "updated_at"]
