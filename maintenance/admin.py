"""Admin of the maintenance app: plans and work orders are edited here; counters, history and
error records are read-only."""

from django.contrib import admin

from maintenance.models import (
    ErrorRecord,
    ServiceEvent,
    ServiceMove,
    ServicePlan,
    VehicleCounters,
    WorkOrder,
    WorkOrderAttachment,
)


@admin.register(ServicePlan)
class ServicePlanAdmin(admin.ModelAdmin[ServicePlan]):
    list_display = [
        "name",
        "vehicle_type",
        "vehicle",
        "interval_hours",
        "interval_km",
        "interval_cycles",
        "interval_days",
        "takes_out_of_service",
        "is_active",
    ]
    list_filter = ["is_active", "takes_out_of_service", "vehicle_type"]


class AttachmentInline(admin.TabularInline[WorkOrderAttachment, WorkOrder]):
    model = WorkOrderAttachment
    extra = 0


@admin.register(WorkOrder)
class WorkOrderAdmin(admin.ModelAdmin[WorkOrder]):
    list_display = ["__str__", "vehicle", "plan", "status", "due_at", "done_at"]
    list_filter = ["status", "plan"]
    search_fields = ["title", "notes", "vehicle__serial_number"]
    readonly_fields = ["plan", "trigger", "counters", "created_at", "started_at", "done_at"]
    inlines = [AttachmentInline]
    list_select_related = ["vehicle", "plan"]


class ReadOnly:
    def has_add_permission(self, request, obj=None) -> bool:  # type: ignore[no-untyped-def]
        return False

    def has_change_permission(self, request, obj=None) -> bool:  # type: ignore[no-untyped-def]
        return False


@admin.register(VehicleCounters)
class VehicleCountersAdmin(ReadOnly, admin.ModelAdmin[VehicleCounters]):
    list_display = [
        "vehicle",
        "operating_hours",
        "distance_km",
        "charge_cycles",
        "out_of_service",
        "out_of_service_reason",
    ]
    list_select_related = ["vehicle"]


@admin.register(ServiceEvent)
class ServiceEventAdmin(ReadOnly, admin.ModelAdmin[ServiceEvent]):
    list_display = ["vehicle", "kind", "at", "detail", "work_order"]
    list_filter = ["kind"]
    list_select_related = ["vehicle"]


@admin.register(ErrorRecord)
class ErrorRecordAdmin(ReadOnly, admin.ModelAdmin[ErrorRecord]):
    list_display = ["vehicle", "error_type", "error_level", "started_at", "ended_at"]
    list_filter = ["error_level", "error_type"]
    search_fields = ["error_type", "description"]
    list_select_related = ["vehicle"]


@admin.register(ServiceMove)
class ServiceMoveAdmin(ReadOnly, admin.ModelAdmin[ServiceMove]):
    list_display = ["__str__", "vehicle", "station", "status", "reason", "created_at", "ended_at"]
    list_filter = ["status"]
    list_select_related = ["vehicle", "station"]
