"""Read API of vehicles. Commands to vehicles (pause, resume, charge, park, instant actions) are
in `orders.api.vehicle_views`, because they are recorded and audited with the orders."""

from typing import Any

from django.db.models import QuerySet
from drf_spectacular.utils import extend_schema
from rest_framework import serializers, viewsets
from rest_framework.request import Request
from rest_framework.response import Response

from robots.api.serializers import VehicleSerializer
from robots.models import Vehicle


class VehicleViewSet(viewsets.ReadOnlyModelViewSet[Vehicle]):
    """Vehicles with their latest state (at most about a second old)."""

    queryset = Vehicle.objects.all()
    serializer_class = VehicleSerializer
    lookup_value_regex = "[0-9]{1,18}"

    class FilterSerializer(serializers.Serializer[dict[str, Any]]):
        connection = serializers.ChoiceField(choices=Vehicle.Connection.choices, required=False)
        map_id = serializers.CharField(required=False)
        manufacturer = serializers.CharField(required=False)

    @extend_schema(parameters=[FilterSerializer])
    def list(self, request: Request, *args: Any, **kwargs: Any) -> Response:
        return super().list(request, *args, **kwargs)

    def get_queryset(self) -> QuerySet[Vehicle]:
        vehicles = super().get_queryset()
        if self.action != "list":
            return vehicles
        filters = self.FilterSerializer(data=self.request.query_params)
        filters.is_valid(raise_exception=True)
        return vehicles.filter(**filters.validated_data)
