"""Admin for transport orders."""

from typing import Any

from django.contrib import admin
from django.http import HttpRequest

from orders import services
from orders.models import OrderEvent, TransportOrder


class OrderEventInline(admin.TabularInline[OrderEvent, TransportOrder]):
    model = OrderEvent
    extra = 0
    can_delete = False
    readonly_fields = ["kind", "at", "detail"]

    def has_add_permission(self, request: object, obj: object = None) -> bool:
        return False


@admin.register(TransportOrder)
class TransportOrderAdmin(admin.ModelAdmin[TransportOrder]):
    list_display = [
        "__str__",
        "source",
        "destination",
        "status",
        "vehicle",
        "priority",
        "created_at",
        "finished_at",
    ]
    list_filter = ["status", "source__map"]
    search_fields = ["external_ref", "load_id", "vda_order_id"]
    raw_id_fields = ["source", "destination", "vehicle"]
    readonly_fields = [
        "status",
        "vehicle",
        "route",
        "vda_order_id",
        "failure_reason",
        "cancel_requested",
        "assigned_at",
        "started_at",
        "finished_at",
        "created_by",
    ]
    inlines = [OrderEventInline]

    def save_model(
        self, request: HttpRequest, obj: TransportOrder, form: Any, change: bool
    ) -> None:
        """New orders go through the service (validation, timeline, dispatch), never a bare save."""
        if change:
            super().save_model(request, obj, form, change)
            return
        created = services.create_transport_order(
            source=obj.source,
            destination=obj.destination,
            priority=obj.priority,
            load_id=obj.load_id,
            load_type=obj.load_type,
            external_ref=obj.external_ref,
            created_by=request.user,
        )
        obj.pk = created.pk
