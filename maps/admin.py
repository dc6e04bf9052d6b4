"""Admin for layouts."""

from django.contrib import admin

from maps.models import Edge, Map, Node, Station


@admin.register(Map)
class MapAdmin(admin.ModelAdmin[Map]):
    list_display = ["map_id", "name", "updated_at"]
    search_fields = ["map_id", "name"]


@admin.register(Node)
class NodeAdmin(admin.ModelAdmin[Node]):
    list_display = ["node_id", "map", "x", "y", "theta"]
    list_filter = ["map"]
    search_fields = ["node_id"]


@admin.register(Edge)
class EdgeAdmin(admin.ModelAdmin[Edge]):
    list_display = ["edge_id", "map", "start", "end", "length", "max_speed"]
    list_filter = ["map"]
    search_fields = ["edge_id"]
    raw_id_fields = ["start", "end"]


@admin.register(Station)
class StationAdmin(admin.ModelAdmin[Station]):
    list_display = ["station_id", "name", "kind", "map", "node"]
    list_filter = ["map", "kind"]
    search_fields = ["station_id", "name"]
    raw_id_fields = ["node"]
