"""Output serializers of the orders API (inputs are nested in the views that take them)."""

import json
from typing import Any

from drf_spectacular.utils import extend_schema_field
from rest_framework import serializers

from orders.models import (
    OrderEvent,
    OrderStep,
    TransportOrder,
    VehicleCommand,
    WebhookSubscription,
)


class OrderEventSerializer(serializers.ModelSerializer[OrderEvent]):
    class Meta:
        model = OrderEvent
        fields = ["kind", "at", "detail"]


class OrderStepSerializer(serializers.ModelSerializer[OrderStep]):
    """One stop: station id, operation, the custom action type and parameters, when it was done."""

    station = serializers.CharField(source="station.station_id", read_only=True)

    class Meta:
        model = OrderStep
        fields = ["index", "station", "operation", "action_type", "parameters", "finished_at"]
        read_only_fields = fields


class TransportOrderSerializer(serializers.ModelSerializer[TransportOrder]):
    """A transport order with its timeline; stations and vehicle by their ids in the layout."""

    source = serializers.CharField(source="source.station_id", read_only=True)  # type: ignore[assignment]
    destination = serializers.CharField(source="destination.station_id", read_only=True)
    map = serializers.CharField(source="source.map.map_id", read_only=True)
    vehicle = serializers.CharField(
        source="vehicle.serial_number", default=None, read_only=True, allow_null=True
    )
    vehicle_id = serializers.IntegerField(read_only=True, allow_null=True)
    intended_vehicle = serializers.CharField(
        source="intended_vehicle.serial_number", default=None, read_only=True, allow_null=True
    )
    vehicle_type = serializers.CharField(
        source="vehicle_type.type_id", default=None, read_only=True, allow_null=True
    )
    steps = OrderStepSerializer(many=True, read_only=True)
    sequence = serializers.CharField(
        source="sequence.reference", default=None, read_only=True, allow_null=True
    )
    sequence_index = serializers.IntegerField(read_only=True, allow_null=True)
    events = OrderEventSerializer(many=True, read_only=True)

    class Meta:
        model = TransportOrder
        fields = [
            "id",
            "source",
            "destination",
            "map",
            "steps",
            "intended_vehicle",
            "vehicle_type",
            "metadata",
            "sequence",
            "sequence_index",
            "load_id",
            "load_type",
            "priority",
            "external_ref",
            "earliest_start",
            "deadline",
            "status",
            "dispatch_note",
            "vehicle",
            "vehicle_id",
            "route",
            "route_steps",
            "failure_reason",
            "cancel_requested",
            "created_at",
            "assigned_at",
            "started_at",
            "finished_at",
            "events",
        ]
        read_only_fields = fields


class VehicleCommandSerializer(serializers.ModelSerializer[VehicleCommand]):
    """A command as queued for control."""

    class Meta:
        model = VehicleCommand
        fields = [
            "id",
            "vehicle",
            "kind",
            "parameters",
            "status",
            "result",
            "action_id",
            "created_at",
            "updated_at",
        ]
        read_only_fields = fields


class WebhookSubscriptionSerializer(serializers.ModelSerializer[WebhookSubscription]):
    """A subscription without its secret (the secret is shown once, when it is created)."""

    events = serializers.ListField(child=serializers.CharField(), read_only=True)

    class Meta:
        model = WebhookSubscription
        fields = [
            "id",
            "url",
            "events",
            "description",
            "own_orders_only",
            "is_active",
            "created_at",
        ]
        read_only_fields = fields


class WebhookSubscriptionCreatedSerializer(WebhookSubscriptionSerializer):
    """The answer to creating a subscription: with the signing secret, shown this once."""

    class Meta(WebhookSubscriptionSerializer.Meta):
        fields = [*WebhookSubscriptionSerializer.Meta.fields, "secret"]
        read_only_fields = fields


@extend_schema_field(
    {
        "oneOf": [
            {"type": "string"},
            {"type": "number"},
            {"type": "boolean"},
            {"type": "array", "items": {}},
            {"type": "object"},
        ]
    }
)
class ParameterValueField(serializers.JSONField):
    """The value of an action parameter: any JSON value but null."""


def validate_json_parameters(value: Any) -> Any:
    """Parameters of an instant action: a small JSON object of plain values without NUL
    characters (PostgreSQL cannot store those in JSON)."""
    if not isinstance(value, dict):
        raise serializers.ValidationError("Expected an object of parameters.")
    text = json.dumps(value)
    if len(text) > 4000:
        raise serializers.ValidationError("At most 4000 characters of parameters.")
    if "\\u0000" in text:
        raise serializers.ValidationError("Null characters are not allowed.")
    if any(len(key) > 100 or not key for key in value):
        raise serializers.ValidationError("Parameter keys have 1 to 100 characters.")
    return value
