"""Read API of the maintenance app: plans, work orders, counters, history and error figures."""

from dataclasses import asdict
from typing import Any

from django.db.models import QuerySet
from django.shortcuts import get_object_or_404
from drf_spectacular.utils import extend_schema
from rest_framework import generics, serializers
from rest_framework.request import Request
from rest_framework.response import Response
from rest_framework.views import APIView

from maintenance import selectors
from maintenance.api.serializers import (
    ErrorRecordSerializer,
    ServiceEventSerializer,
    ServicePlanSerializer,
    VehicleCountersSerializer,
    WorkOrderSerializer,
)
from maintenance.models import ErrorRecord, ServicePlan, VehicleCounters, WorkOrder
from robots.models import Vehicle


class ServicePlanListApi(generics.ListAPIView[ServicePlan]):
    """Service plans."""

    serializer_class = ServicePlanSerializer
    queryset = ServicePlan.objects.select_related("vehicle_type")


class WorkOrderListApi(generics.ListAPIView[WorkOrder]):
    """Work orders, latest due first; `?status=` and `?vehicle=` narrow them."""

    serializer_class = WorkOrderSerializer

    class FilterSerializer(serializers.Serializer[dict[str, Any]]):
        status = serializers.ChoiceField(choices=WorkOrder.Status.choices, required=False)
        vehicle = serializers.IntegerField(required=False, min_value=1)

    @extend_schema(parameters=[FilterSerializer])
    def get(self, request: Request, *args: Any, **kwargs: Any) -> Response:
        return super().get(request, *args, **kwargs)

    def get_queryset(self) -> QuerySet[WorkOrder]:
        filters = self.FilterSerializer(data=self.request.query_params)
        filters.is_valid(raise_exception=True)
        return WorkOrder.objects.prefetch_related("attachments").filter(**filters.validated_data)


class VehicleCountersListApi(generics.ListAPIView[VehicleCounters]):
    """Counters kept from state and whether staff took the vehicle out of service."""

    serializer_class = VehicleCountersSerializer
    queryset = VehicleCounters.objects.order_by("vehicle_id")


class ServiceHistoryApi(generics.ListAPIView[Any]):
    """A vehicle's maintenance history, newest first."""

    serializer_class = ServiceEventSerializer

    def get_queryset(self) -> Any:
        vehicle = get_object_or_404(Vehicle, pk=self.kwargs["pk"])
        return selectors.service_history(vehicle=vehicle, limit=10_000)


class VehicleErrorsApi(APIView):
    """A vehicle's error figures (counts, MTBF in operating hours per FATAL error, top types)
    and its latest error records."""

    @extend_schema(responses={200: dict})
    def get(self, request: Request, pk: int) -> Response:
        vehicle = get_object_or_404(Vehicle, pk=pk)
        records = ErrorRecord.objects.filter(vehicle=vehicle)[:100]
        return Response(
            {
                "stats": asdict(selectors.error_stats(vehicle=vehicle)),
                "reasons_unavailable": selectors.out_of_service(vehicle_ids=[vehicle.pk]).get(
                    vehicle.pk
                ),
                "records": ErrorRecordSerializer(records, many=True).data,
            }
        )
