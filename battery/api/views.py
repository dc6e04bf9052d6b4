"""Read API of the battery app: vehicles' battery state, history, chargers, charge sessions."""

from typing import Any

from django.db.models import QuerySet
from django.shortcuts import get_object_or_404
from drf_spectacular.utils import extend_schema
from rest_framework import generics, serializers
from rest_framework.request import Request
from rest_framework.response import Response

from battery import selectors
from battery.api.serializers import (
    BatterySampleSerializer,
    ChargerSerializer,
    ChargeSessionSerializer,
    VehicleEnergySerializer,
)
from battery.models import Charger, ChargeSession
from robots.models import Vehicle


class ChargerListApi(generics.ListAPIView[Charger]):
    """Chargers, their points and which vehicle holds each booked point."""

    serializer_class = ChargerSerializer
    queryset = Charger.objects.select_related("station__map").prefetch_related("vehicle_types")

    def get_serializer_context(self) -> dict[str, Any]:
        return {**super().get_serializer_context(), "booked": selectors.booked_vehicles()}


class ChargeSessionListApi(generics.ListAPIView[ChargeSession]):
    """Charge sessions, newest first; `?status=` and `?vehicle=` narrow them."""

    serializer_class = ChargeSessionSerializer

    class FilterSerializer(serializers.Serializer[dict[str, Any]]):
        status = serializers.ChoiceField(choices=ChargeSession.Status.choices, required=False)
        vehicle = serializers.IntegerField(required=False, min_value=1)

    @extend_schema(parameters=[FilterSerializer])
    def get(self, request: Request, *args: Any, **kwargs: Any) -> Response:
        return super().get(request, *args, **kwargs)

    def get_queryset(self) -> QuerySet[ChargeSession]:
        filters = self.FilterSerializer(data=self.request.query_params)
        filters.is_valid(raise_exception=True)
        return ChargeSession.objects.select_related("charger__station").filter(
            **filters.validated_data
        )


class VehicleEnergyListApi(generics.ListAPIView[Any]):
    """Every vehicle's battery: charge, band, learned consumption, cycles, health, session."""

    serializer_class = VehicleEnergySerializer

    def get_queryset(self) -> Any:
        return selectors.list_vehicle_energy()


class BatteryHistoryApi(generics.ListAPIView[Any]):
    """Sampled battery history of one vehicle, newest first."""

    serializer_class = BatterySampleSerializer

    def get_queryset(self) -> Any:
        vehicle = get_object_or_404(Vehicle, pk=self.kwargs["pk"])
        return selectors.battery_history(vehicle=vehicle, limit=10_000)
