"""Serializers of maintenance state (read only)."""

from typing import Any

from rest_framework import serializers

from maintenance.models import ErrorRecord, ServiceEvent, ServicePlan, VehicleCounters, WorkOrder


class ServicePlanSerializer(serializers.ModelSerializer[ServicePlan]):
    vehicle_type: serializers.SlugRelatedField[Any] = serializers.SlugRelatedField(
        read_only=True, slug_field="type_id"
    )

    class Meta:
        model = ServicePlan
        fields = [
            "id",
            "name",
            "vehicle_type",
            "vehicle",
            "interval_hours",
            "interval_km",
            "interval_cycles",
            "interval_days",
            "grace_days",
            "takes_out_of_service",
            "is_active",
        ]
        read_only_fields = fields


class WorkOrderSerializer(serializers.ModelSerializer[WorkOrder]):
    attachments = serializers.SerializerMethodField()

    class Meta:
        model = WorkOrder
        fields = [
            "id",
            "vehicle",
            "plan",
            "title",
            "status",
            "takes_out_of_service",
            "trigger",
            "counters",
            "notes",
            "parts",
            "attachments",
            "due_at",
            "created_at",
            "started_at",
            "done_at",
        ]
        read_only_fields = fields

    def get_attachments(self, work_order: WorkOrder) -> list[dict[str, Any]]:
        return [
            {"name": a.file.name, "description": a.description, "uploaded_at": a.uploaded_at}
            for a in work_order.attachments.all()
        ]


class VehicleCountersSerializer(serializers.ModelSerializer[VehicleCounters]):
    operating_hours = serializers.FloatField(read_only=True)
    distance_km = serializers.FloatField(read_only=True)

    class Meta:
        model = VehicleCounters
        fields = [
            "vehicle",
            "operating_hours",
            "driving_seconds",
            "distance_km",
            "charge_cycles",
            "out_of_service",
            "out_of_service_reason",
            "out_of_service_since",
        ]
        read_only_fields = fields


class ServiceEventSerializer(serializers.ModelSerializer[ServiceEvent]):
    class Meta:
        model = ServiceEvent
        fields = ["kind", "at", "detail", "work_order"]
        read_only_fields = fields


class ErrorRecordSerializer(serializers.ModelSerializer[ErrorRecord]):
    class Meta:
        model = ErrorRecord
        fields = ["error_type", "error_level", "description", "started_at", "ended_at"]
        read_only_fields = fields
