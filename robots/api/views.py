"""Read API of vehicles (commands to vehicles follow with the orders API, issue 5)."""

from rest_framework import viewsets

from robots.api.serializers import VehicleSerializer
from robots.models import Vehicle


class VehicleViewSet(viewsets.ReadOnlyModelViewSet[Vehicle]):
    queryset = Vehicle.objects.all()
    serializer_class = VehicleSerializer
