"""Commands to vehicles: pause, resume, send to charge or park, instant actions.

Each answers 202 with the queued command: `control` carries it out, and the vehicle's state
(`GET /api/v1/vehicles/<id>/`) shows the outcome.
"""

from typing import Any

from django.shortcuts import get_object_or_404
from drf_spectacular.utils import (
    OpenApiExample,
    OpenApiResponse,
    extend_schema,
    extend_schema_serializer,
)
from rest_framework import serializers, status
from rest_framework.request import Request
from rest_framework.response import Response
from rest_framework.views import APIView

from maps.models import Station
from orders import services
from orders.api.serializers import (
    ParameterValueField,
    VehicleCommandSerializer,
    validate_json_parameters,
)
from orders.models import VehicleCommand
from robots.models import Vehicle

RESPONSES = {
    202: VehicleCommandSerializer,
    409: OpenApiResponse(description="The vehicle is not connected, busy or unavailable."),
    422: OpenApiResponse(description="No such station reachable, or an action it lacks."),
}


def _accepted(command: VehicleCommand) -> Response:
    return Response(VehicleCommandSerializer(command).data, status=status.HTTP_202_ACCEPTED)


class VehiclePauseApi(APIView):
    """Pause the vehicle (VDA 5050 startPause); dispatch skips it while paused."""

    @extend_schema(request=None, responses=RESPONSES)
    def post(self, request: Request, pk: int) -> Response:
        vehicle = get_object_or_404(Vehicle, pk=pk)
        return _accepted(services.pause_vehicle(vehicle=vehicle, by=request.user))


class VehicleResumeApi(APIView):
    """Let a paused vehicle go on (VDA 5050 stopPause)."""

    @extend_schema(request=None, responses=RESPONSES)
    def post(self, request: Request, pk: int) -> Response:
        vehicle = get_object_or_404(Vehicle, pk=pk)
        return _accepted(services.resume_vehicle(vehicle=vehicle, by=request.user))


class StationInputSerializer(serializers.Serializer[dict[str, Any]]):
    station = serializers.CharField(
        max_length=100, required=False, help_text="station id; the nearest one when left out"
    )


def _station(vehicle: Vehicle, data: dict[str, Any]) -> Station | None:
    if "station" not in data:
        return None
    station = (
        Station.objects.filter(map__map_id=vehicle.map_id, station_id=data["station"])
        .select_related("map", "node")
        .first()
    )
    if station is None:
        raise serializers.ValidationError({"station": [f"No station {data['station']!r}."]})
    return station


class VehicleChargeApi(APIView):
    """Send an idle vehicle to a charging station."""

    @extend_schema(request=StationInputSerializer, responses=RESPONSES)
    def post(self, request: Request, pk: int) -> Response:
        vehicle = get_object_or_404(Vehicle, pk=pk)
        data = StationInputSerializer(data=request.data)
        data.is_valid(raise_exception=True)
        station = _station(vehicle, data.validated_data)
        command = services.send_vehicle_to_charge(vehicle=vehicle, station=station, by=request.user)
        return _accepted(command)


class VehicleParkApi(APIView):
    """Send an idle vehicle to a parking station."""

    @extend_schema(request=StationInputSerializer, responses=RESPONSES)
    def post(self, request: Request, pk: int) -> Response:
        vehicle = get_object_or_404(Vehicle, pk=pk)
        data = StationInputSerializer(data=request.data)
        data.is_valid(raise_exception=True)
        station = _station(vehicle, data.validated_data)
        command = services.send_vehicle_to_park(vehicle=vehicle, station=station, by=request.user)
        return _accepted(command)


class VehicleInstantActionApi(APIView):
    """Send one VDA 5050 instant action (e.g. `stateRequest`, `initPosition`, `startCharging`)."""

    @extend_schema_serializer(component_name="VehicleInstantAction")
    class InputSerializer(serializers.Serializer[dict[str, Any]]):
        action_type = serializers.CharField(max_length=64)
        parameters = serializers.DictField(
            child=ParameterValueField(),
            default=dict,
            validators=[validate_json_parameters],
            help_text="actionParameters as an object: key → value",
        )

    @extend_schema(
        request=InputSerializer,
        responses=RESPONSES,
        examples=[
            OpenApiExample(
                "Set the position",
                request_only=True,
                value={
                    "action_type": "initPosition",
                    "parameters": {"x": 3.0, "y": 6.0, "theta": 0.0, "mapId": "demo"},
                },
            ),
            OpenApiExample(
                "Ask for a fresh state", request_only=True, value={"action_type": "stateRequest"}
            ),
        ],
    )
    def post(self, request: Request, pk: int) -> Response:
        vehicle = get_object_or_404(Vehicle, pk=pk)
        data = self.InputSerializer(data=request.data)
        data.is_valid(raise_exception=True)
        command = services.request_instant_action(
            vehicle=vehicle,
            action_type=data.validated_data["action_type"],
            parameters=data.validated_data["parameters"],
            by=request.user,
        )
        return _accepted(command)


class VehicleCommandListApi(APIView):
    """The vehicle's latest commands with their outcome (queued, sent, refused with the reason,
    running, finished, failed), newest first."""

    @extend_schema(responses=VehicleCommandSerializer(many=True))
    def get(self, request: Request, pk: int) -> Response:
        vehicle = get_object_or_404(Vehicle, pk=pk)
        commands = VehicleCommand.objects.filter(vehicle=vehicle)[:50]
        return Response(VehicleCommandSerializer(commands, many=True).data)
