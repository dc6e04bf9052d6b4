"""Admin for the report tables (read-only: Celery maintains them)."""

from django.contrib import admin
from django.http import HttpRequest

from reports.models import ErrorCount, LeadTimeCount, VehicleHour


class ReadOnlyAdmin(admin.ModelAdmin):  # type: ignore[type-arg]
    def has_add_permission(self, request: HttpRequest) -> bool:
        return False

    def has_change_permission(self, request: HttpRequest, obj: object = None) -> bool:
        return False


@admin.register(VehicleHour)
class VehicleHourAdmin(ReadOnlyAdmin):
    list_display = ["hour", "vehicle", "finished", "failed", "busy_s", "idle_s", "distance_m"]
    list_filter = ["vehicle"]
    date_hierarchy = "hour"


@admin.register(LeadTimeCount)
class LeadTimeCountAdmin(ReadOnlyAdmin):
    list_display = ["day", "vehicle", "stage", "bucket", "count"]
    list_filter = ["stage"]
    date_hierarchy = "day"


@admin.register(ErrorCount)
class ErrorCountAdmin(ReadOnlyAdmin):
    list_display = ["day", "vehicle", "error_type", "count"]
    list_filter = ["error_type"]
    date_hierarchy = "day"
