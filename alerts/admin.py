"""Admin of alerts and escalation rules."""

from django.contrib import admin
from django.db import models

from alerts.models import Alert, AlertNotification, EscalationRule


class NotificationInline(admin.TabularInline[AlertNotification, Alert]):
    model = AlertNotification
    extra = 0
    can_delete = False
    readonly_fields = ["rule", "sent_at", "email_sent", "webhook_status", "error"]


@admin.register(Alert)
class AlertAdmin(admin.ModelAdmin[Alert]):
    list_display = [
        "raised_at",
        "severity",
        "source",
        "status",
        "vehicle",
        "order_ref",
        "message",
        "occurrences",
    ]
    list_filter = ["status", "severity", "source", "auto_resolved"]
    search_fields = ["cause", "message", "order_ref"]
    date_hierarchy = "raised_at"
    inlines = [NotificationInline]
    # Alerts change only through the services (dedup, audit): the admin reads them.
    readonly_fields = [f.name for f in Alert._meta.fields]

    def has_add_permission(self, request: object) -> bool:
        return False


@admin.register(EscalationRule)
class EscalationRuleAdmin(admin.ModelAdmin[EscalationRule]):
    list_display = [
        "name",
        "active",
        "min_severity",
        "source",
        "after_minutes",
        "email_to",
        "webhook_url",
    ]
    list_filter = ["active", "min_severity"]
    formfield_overrides = {models.URLField: {"assume_scheme": "https"}}
