"""ERP API of the inventory (issue 8): "where is load L" and "move load L to station S".

These views belong to the orders layer because a move creates a transport order; the read
goes through `inventory.selectors`.
"""

from typing import Any

from django.http import Http404
from drf_spectacular.utils import OpenApiResponse, extend_schema, extend_schema_serializer
from rest_framework import serializers, status
from rest_framework.request import Request
from rest_framework.response import Response
from rest_framework.views import APIView

from inventory import selectors as inventory_selectors
from inventory.models import LoadCarrier
from maps.models import Station
from orders.api.serializers import TransportOrderSerializer
from orders.services.floor import move_load_to


class LoadLocationSerializer(serializers.Serializer[LoadCarrier]):
    """Where a load is: at a station (with slot), on a vehicle, or unknown."""

    load_id = serializers.CharField()
    load_type = serializers.CharField()
    place = serializers.SerializerMethodField()
    station = serializers.SerializerMethodField()
    map = serializers.SerializerMethodField()
    slot = serializers.IntegerField(allow_null=True)
    vehicle = serializers.SerializerMethodField()
    updated_at = serializers.DateTimeField()

    def get_place(self, load: LoadCarrier) -> str:
        return "STATION" if load.location_id else "VEHICLE" if load.vehicle_id else "UNKNOWN"

    def get_station(self, load: LoadCarrier) -> str | None:
        return load.location.station.station_id if load.location else None

    def get_map(self, load: LoadCarrier) -> str | None:
        return load.location.station.map.map_id if load.location else None

    def get_vehicle(self, load: LoadCarrier) -> str | None:
        return load.vehicle.serial_number if load.vehicle else None


def _load(load_id: str) -> LoadCarrier:
    load = inventory_selectors.find_load(load_id)
    if load is None:
        raise Http404(f"no load {load_id!r}")
    return load


class LoadLocationApi(APIView):
    """Where is load `load_id`?"""

    @extend_schema(responses={200: LoadLocationSerializer, 404: OpenApiResponse()})
    def get(self, request: Request, load_id: str) -> Response:
        return Response(LoadLocationSerializer(_load(load_id)).data)


class LoadMoveApi(APIView):
    """Move load `load_id` to a station: the inventory knows where it is, so the ERP names only
    the destination. Creates a transport order (201) like `POST /orders/`."""

    @extend_schema_serializer(component_name="LoadMove")
    class InputSerializer(serializers.Serializer[dict[str, Any]]):
        station = serializers.CharField(max_length=100, help_text="destination station id")
        map = serializers.CharField(max_length=100, required=False, help_text="map id")
        priority = serializers.IntegerField(min_value=-1000, max_value=1000, default=0)
        external_ref = serializers.CharField(max_length=200, default="", allow_blank=True)
        deadline = serializers.DateTimeField(required=False, allow_null=True)

    @extend_schema(
        request=InputSerializer,
        responses={201: TransportOrderSerializer, 404: OpenApiResponse(), 422: OpenApiResponse()},
    )
    def post(self, request: Request, load_id: str) -> Response:
        data = self.InputSerializer(data=request.data)
        data.is_valid(raise_exception=True)
        values = data.validated_data
        load = _load(load_id)
        stations = Station.objects.filter(station_id=values["station"])
        if "map" in values:
            stations = stations.filter(map__map_id=values["map"])
        elif load.location is not None:
            stations = stations.filter(map_id=load.location.station.map_id)
        found = list(stations[:2])
        if len(found) != 1:
            problem = "No station" if not found else "Several stations are named"
            raise serializers.ValidationError({"station": [f"{problem} {values['station']!r}."]})
        order = move_load_to(
            load_id=load.load_id,
            destination=found[0],
            priority=values["priority"],
            external_ref=values["external_ref"],
            deadline=values.get("deadline"),
            created_by=request.user,
        )
        return Response(TransportOrderSerializer(order).data, status=status.HTTP_201_CREATED)
