"""Admin for transport orders, integration clients and tokens, webhooks and vehicle commands."""

from typing import Any

from django.contrib import admin, messages
from django.db import models
from django.db.models import QuerySet
from django.http import HttpRequest

from orders import services
from orders.models import (
    ApiToken,
    IdempotencyKey,
    IntegrationClient,
    OrderEvent,
    TransportOrder,
    VehicleCommand,
    WebhookAttempt,
    WebhookDelivery,
    WebhookSubscription,
)


class ReadOnlyInline(admin.TabularInline):  # type: ignore[type-arg]
    extra = 0
    can_delete = False

    def has_add_permission(self, request: HttpRequest, obj: object = None) -> bool:
        return False

    def has_change_permission(self, request: HttpRequest, obj: object = None) -> bool:
        return False


class OrderEventInline(ReadOnlyInline):
    model = OrderEvent
    fields = readonly_fields = (
        "kind",
        "at",
        "detail",
    )


@admin.register(TransportOrder)
class TransportOrderAdmin(admin.ModelAdmin[TransportOrder]):
    list_display = [
        "__str__",
        "source",
        "destination",
        "status",
        "vehicle",
        "priority",
        "deadline",
        "dispatch_note",
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
        "dispatch_note",
        "failure_reason",
        "cancel_requested",
        "assigned_at",
        "sent_at",
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
            earliest_start=obj.earliest_start,
            deadline=obj.deadline,
            created_by=request.user,
        )
        obj.pk = created.pk


class ApiTokenInline(ReadOnlyInline):
    model = ApiToken
    fields = readonly_fields = (
        "prefix",
        "created_at",
        "expires_at",
        "last_used_at",
        "revoked_at",
    )


@admin.register(IntegrationClient)
class IntegrationClientAdmin(admin.ModelAdmin[IntegrationClient]):
    list_display = ["name", "is_active", "created_at"]
    fields = ["name", "description", "is_active", "user"]
    readonly_fields = ["user"]
    inlines = [ApiTokenInline]
    actions = ["issue_token"]

    def save_model(
        self, request: HttpRequest, obj: IntegrationClient, form: Any, change: bool
    ) -> None:
        """A new client gets its own user through the service."""
        if change:
            super().save_model(request, obj, form, change)
            return
        created = services.create_integration_client(name=obj.name, description=obj.description)
        obj.pk, obj.user = created.pk, created.user

    @admin.action(description="Issue a new API token (shown once)")
    def issue_token(self, request: HttpRequest, queryset: QuerySet[IntegrationClient]) -> None:
        for client in queryset:
            _, key = services.issue_api_token(client=client)
            self.message_user(
                request,
                f"Token for {client}: {key} (copy it now, it is not shown again)",
                messages.WARNING,
            )


@admin.register(ApiToken)
class ApiTokenAdmin(admin.ModelAdmin[ApiToken]):
    list_display = ["__str__", "client", "created_at", "expires_at", "last_used_at", "revoked_at"]
    list_filter = ["client"]
    readonly_fields = ["client", "key_hash", "prefix", "created_at", "last_used_at", "revoked_at"]
    actions = ["revoke"]

    def has_add_permission(self, request: HttpRequest) -> bool:
        return False  # issued from the client's page, so that the key can be shown once

    @admin.action(description="Revoke the selected tokens")
    def revoke(self, request: HttpRequest, queryset: QuerySet[ApiToken]) -> None:
        for token in queryset:
            services.revoke_api_token(token=token)


@admin.register(WebhookSubscription)
class WebhookSubscriptionAdmin(admin.ModelAdmin[WebhookSubscription]):
    list_display = ["client", "url", "events", "own_orders_only", "is_active", "created_at"]
    list_filter = ["is_active", "client"]
    readonly_fields = ["secret", "created_at"]
    formfield_overrides = {models.URLField: {"assume_scheme": "https"}}

    def save_model(
        self, request: HttpRequest, obj: WebhookSubscription, form: Any, change: bool
    ) -> None:
        """New subscriptions go through the service, which checks events and makes the secret."""
        if change:
            super().save_model(request, obj, form, change)
            return
        created = services.create_webhook_subscription(
            client=obj.client,
            url=obj.url,
            events=list(obj.events),
            description=obj.description,
            own_orders_only=obj.own_orders_only,
        )
        if not obj.is_active:
            created.is_active = False
            created.save(update_fields=["is_active"])
        obj.pk, obj.secret = created.pk, created.secret


class WebhookAttemptInline(ReadOnlyInline):
    model = WebhookAttempt
    fields = readonly_fields = (
        "at",
        "status_code",
        "duration_ms",
        "error",
        "response_excerpt",
    )


@admin.register(WebhookDelivery)
class WebhookDeliveryAdmin(admin.ModelAdmin[WebhookDelivery]):
    list_display = ["event_type", "subscription", "status", "attempts", "next_attempt_at"]
    list_filter = ["status", "event_type", "subscription__client"]
    readonly_fields = [
        "subscription",
        "event_id",
        "event_type",
        "payload",
        "status",
        "attempts",
        "next_attempt_at",
        "created_at",
        "delivered_at",
    ]
    inlines = [WebhookAttemptInline]
    actions = ["retry_now"]

    def has_add_permission(self, request: HttpRequest) -> bool:
        return False

    @admin.action(description="Send again now")
    def retry_now(self, request: HttpRequest, queryset: QuerySet[WebhookDelivery]) -> None:
        services.retry_webhook_deliveries(delivery_ids=[d.pk for d in queryset])


@admin.register(IdempotencyKey)
class IdempotencyKeyAdmin(admin.ModelAdmin[IdempotencyKey]):
    list_display = ["key", "user", "request_path", "state", "response_status", "created_at"]
    list_filter = ["state"]
    search_fields = ["key"]

    def has_add_permission(self, request: HttpRequest) -> bool:
        return False

    def has_change_permission(self, request: HttpRequest, obj: object = None) -> bool:
        return False


@admin.register(VehicleCommand)
class VehicleCommandAdmin(admin.ModelAdmin[VehicleCommand]):
    list_display = ["__str__", "kind", "vehicle", "requested_by", "created_at"]
    list_filter = ["kind"]

    def has_add_permission(self, request: HttpRequest) -> bool:
        return False

    def has_change_permission(self, request: HttpRequest, obj: object = None) -> bool:
        return False
