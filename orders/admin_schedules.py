"""Admin for order sequences and recurring orders (registered when `orders.admin` loads)."""

from typing import Any

from django import forms
from django.contrib import admin
from django.http import HttpRequest

from fleet.exceptions import DomainError
from orders import services
from orders.admin import ReadOnlyInline
from orders.models import OrderSequence, RecurringOrder, RecurringOrderRun


@admin.register(OrderSequence)
class OrderSequenceAdmin(admin.ModelAdmin[OrderSequence]):
    """Order sequences are made by the API (`sequence`); here to look them up."""

    list_display = ["reference", "vehicle", "created_at"]
    search_fields = ["reference"]
    readonly_fields = ["reference", "vehicle", "created_at"]


class RecurringOrderForm(forms.ModelForm):  # type: ignore[type-arg]
    class Meta:
        model = RecurringOrder
        fields = [
            "name",
            "is_active",
            "map",
            "steps",
            "priority",
            "load_type",
            "vehicle_type",
            "interval_minutes",
            "weekdays",
            "window_start",
            "window_end",
        ]

    def clean(self) -> dict[str, Any]:
        cleaned = super().clean() or {}
        if not self.errors:
            candidate = RecurringOrder(**{k: v for k, v in cleaned.items() if k != "id"})
            try:
                services.check_recurring_order(candidate)
            except DomainError as exc:
                raise forms.ValidationError(str(exc)) from None
        return cleaned


class RecurringOrderRunInline(ReadOnlyInline):
    model = RecurringOrderRun
    fields = readonly_fields = ("slot", "order", "error", "created_at")
    max_num = 20


@admin.register(RecurringOrder)
class RecurringOrderAdmin(admin.ModelAdmin[RecurringOrder]):
    """Scheduled orders: beat creates one order per due slot (see orders.services.recurring)."""

    form = RecurringOrderForm
    list_display = [
        "name",
        "is_active",
        "map",
        "interval_minutes",
        "weekdays",
        "window_start",
        "window_end",
        "last_slot",
    ]
    list_filter = ["is_active", "map"]
    inlines = [RecurringOrderRunInline]

    def save_model(
        self, request: HttpRequest, obj: RecurringOrder, form: Any, change: bool
    ) -> None:
        if not change:
            obj.created_by = request.user  # type: ignore[assignment]
        services.save_recurring_order(schedule=obj)
