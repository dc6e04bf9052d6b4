"""The ERP API for transport orders: create, list, get, cancel."""

from typing import Any

from django.shortcuts import get_object_or_404
from rest_framework import generics, status
from rest_framework.request import Request
from rest_framework.response import Response
from rest_framework.views import APIView

from orders import services
from orders.api.serializers import (
    TransportOrderCancelSerializer,
    TransportOrderCreateSerializer,
    TransportOrderSerializer,
)
from orders.models import TransportOrder


class TransportOrderListCreateApi(generics.ListAPIView[TransportOrder]):
    """GET: orders, newest first, filterable by `status`. POST: create an order."""

    serializer_class = TransportOrderSerializer

    def get_queryset(self) -> Any:
        orders = TransportOrder.objects.select_related(
            "source", "destination", "vehicle"
        ).prefetch_related("events")
        wanted = self.request.query_params.get("status")
        return orders.filter(status=wanted.upper()) if wanted else orders

    def post(self, request: Request) -> Response:
        data = TransportOrderCreateSerializer(data=request.data)
        data.is_valid(raise_exception=True)
        order = services.create_transport_order(created_by=request.user, **data.validated_data)
        return Response(TransportOrderSerializer(order).data, status=status.HTTP_201_CREATED)


class TransportOrderDetailApi(generics.RetrieveAPIView[TransportOrder]):
    serializer_class = TransportOrderSerializer
    queryset = TransportOrder.objects.select_related("source", "destination", "vehicle")


class TransportOrderCancelApi(APIView):
    def post(self, request: Request, pk: int) -> Response:
        data = TransportOrderCancelSerializer(data=request.data)
        data.is_valid(raise_exception=True)
        order = services.cancel_transport_order(
            order=get_object_or_404(TransportOrder, pk=pk),
            reason=data.validated_data["reason"],
            by=request.user,
        )
        return Response(TransportOrderSerializer(order).data)
