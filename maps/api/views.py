"""Read-only API of maps and stations."""

from typing import Any

from rest_framework import viewsets
from rest_framework.decorators import action
from rest_framework.request import Request
from rest_framework.response import Response

from maps.api.serializers import MapSerializer, StationSerializer
from maps.models import Map, Station
from maps.selectors import layout_as_dict


class MapViewSet(viewsets.ReadOnlyModelViewSet[Map]):
    queryset = Map.objects.all()
    serializer_class = MapSerializer

    @action(detail=True)
    def layout(self, request: Request, *args: Any, **kwargs: Any) -> Response:
        """Nodes, edges and stations of the map as plain data."""
        return Response(layout_as_dict(map=self.get_object()))


class StationViewSet(viewsets.ReadOnlyModelViewSet[Station]):
    queryset = Station.objects.select_related("map", "node")
    serializer_class = StationSerializer
