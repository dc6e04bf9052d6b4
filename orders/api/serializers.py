"""Serializers of transport orders."""

from rest_framework import serializers

from maps.models import Station
from orders.models import OrderEvent, TransportOrder


class OrderEventSerializer(serializers.ModelSerializer[OrderEvent]):
    class Meta:
        model = OrderEvent
        fields = ["kind", "at", "detail"]


class TransportOrderSerializer(serializers.ModelSerializer[TransportOrder]):
    source = serializers.CharField(source="source.station_id")  # type: ignore[assignment]
    destination = serializers.CharField(source="destination.station_id")
    vehicle = serializers.CharField(source="vehicle.serial_number", default=None)
    events = OrderEventSerializer(many=True, read_only=True)

    class Meta:
        model = TransportOrder
        fields = [
            "id",
            "source",
            "destination",
            "load_id",
            "load_type",
            "priority",
            "external_ref",
            "status",
            "vehicle",
            "route",
            "failure_reason",
            "cancel_requested",
            "created_at",
            "assigned_at",
            "started_at",
            "finished_at",
            "events",
        ]


class TransportOrderCreateSerializer(serializers.Serializer[dict[str, object]]):
    """Input of a new order; stations by their station id."""

    source = serializers.SlugRelatedField(  # type: ignore[assignment]
        slug_field="station_id", queryset=Station.objects.all()
    )
    destination = serializers.SlugRelatedField(
        slug_field="station_id", queryset=Station.objects.all()
    )
    priority = serializers.IntegerField(default=0, min_value=-1000, max_value=1000)
    load_id = serializers.CharField(default="", allow_blank=True, max_length=100)
    load_type = serializers.CharField(default="EPAL", max_length=100)
    external_ref = serializers.CharField(default="", allow_blank=True, max_length=200)


class TransportOrderCancelSerializer(serializers.Serializer[dict[str, object]]):
    reason = serializers.CharField(default="", allow_blank=True, max_length=200)
