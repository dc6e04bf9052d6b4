"""Admin for transport orders, integration clients and tokens, webhooks and vehicle commands."""

from typing import Any

from django import forms
from django.contrib import admin, messages
from django.db import models
from django.db.models import QuerySet
from django.http import HttpRequest

from fleet import roles
from fleet.exceptions import DomainError
from orders import services
from orders.models import (
    ApiToken,
    IdempotencyKey,
    IntegrationClient,
    OrderEvent,
    OrderStep,
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


class OrderStepInline(ReadOnlyInline):
    model = OrderStep
    fields = readonly_fields = (
        "index",
        "station",
        "operation",
        "action_type",
        "parameters",
        "finished_at",
    )


@admin.register(TransportOrder)
class TransportOrderAdmin(admin.ModelAdmin[TransportOrder]):
    """Orders; staff create pick → drop orders here (multi-stop ones on the orders page), and
    cancel, reprioritise and reassign them with the actions or by editing priority, deadline
    and intended vehicle, all through the services."""

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
    raw_id_fields = ["source", "destination", "vehicle", "intended_vehicle"]
    actions = ["cancel_orders", "raise_priority", "lower_priority", "release_to_any_vehicle"]
    readonly_fields = [
        "status",
        "vehicle",
        "route",
        "route_steps",
        "sequence",
        "sequence_index",
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
    inlines = [OrderStepInline, OrderEventInline]

    def get_readonly_fields(self, request: HttpRequest, obj: Any = None) -> list[str]:
        # Stops and type are fixed once the order exists (steps live in their own rows).
        fixed = ["source", "destination", "vehicle_type"] if obj is not None else []
        return [*self.readonly_fields, *fixed]

    def save_model(
        self, request: HttpRequest, obj: TransportOrder, form: Any, change: bool
    ) -> None:
        """Orders are created and changed through the services (validation, timeline, dispatch),
        never by a bare save that could overwrite what control wrote meanwhile."""
        if change:
            self._change(request, obj, set(form.changed_data))
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
            intended_vehicle=obj.intended_vehicle,
            vehicle_type=obj.vehicle_type,
            metadata=obj.metadata,
            created_by=request.user,
        )
        obj.pk = created.pk

    def _change(self, request: HttpRequest, obj: TransportOrder, changed: set[str]) -> None:
        try:
            if changed & {"priority", "deadline"}:
                services.update_order_priority(
                    order=obj,
                    priority=obj.priority,
                    deadline=obj.deadline,
                    change_deadline="deadline" in changed,
                    by=request.user,
                )
            if "intended_vehicle" in changed:
                services.reassign_order(order=obj, vehicle=obj.intended_vehicle, by=request.user)
        except DomainError as exc:
            self.message_user(request, str(exc), messages.ERROR)
        plain = changed & {"load_id", "load_type", "external_ref", "earliest_start", "metadata"}
        if plain:
            TransportOrder.objects.filter(pk=obj.pk).update(**{f: getattr(obj, f) for f in plain})

    def _each(self, request: HttpRequest, queryset: QuerySet[TransportOrder], act: Any) -> None:
        done = 0
        for order in queryset:
            try:
                act(order)
                done += 1
            except DomainError as exc:
                self.message_user(request, f"order {order.pk}: {exc}", messages.WARNING)
        if done:
            self.message_user(request, f"{done} order(s) changed")

    @admin.action(description="Cancel the selected orders")
    def cancel_orders(self, request: HttpRequest, queryset: QuerySet[TransportOrder]) -> None:
        self._each(
            request,
            queryset,
            lambda o: services.cancel_transport_order(order=o, reason="admin", by=request.user),
        )

    @admin.action(description="Raise priority by 10")
    def raise_priority(self, request: HttpRequest, queryset: QuerySet[TransportOrder]) -> None:
        self._each(
            request,
            queryset,
            lambda o: services.update_order_priority(
                order=o, priority=min(o.priority + 10, 1000), by=request.user
            ),
        )

    @admin.action(description="Lower priority by 10")
    def lower_priority(self, request: HttpRequest, queryset: QuerySet[TransportOrder]) -> None:
        self._each(
            request,
            queryset,
            lambda o: services.update_order_priority(
                order=o, priority=max(o.priority - 10, -1000), by=request.user
            ),
        )

    @admin.action(description="Give back to dispatch for any vehicle (unsent orders)")
    def release_to_any_vehicle(
        self, request: HttpRequest, queryset: QuerySet[TransportOrder]
    ) -> None:
        self._each(
            request,
            queryset,
            lambda o: services.reassign_order(order=o, vehicle=None, by=request.user),
        )


class ApiTokenInline(ReadOnlyInline):
    model = ApiToken
    fields = readonly_fields = (
        "prefix",
        "created_at",
        "expires_at",
        "last_used_at",
        "revoked_at",
    )


class IntegrationClientForm(forms.ModelForm):  # type: ignore[type-arg]
    """Scopes as one checkbox each (the model keeps them as a JSON list)."""

    scopes = forms.MultipleChoiceField(
        choices=[(name, f"{name}: {text}") for name, (text, _) in roles.API_SCOPES.items()],
        widget=forms.CheckboxSelectMultiple,
        required=False,
        help_text="What the client's tokens may call; nothing else is allowed.",
    )

    class Meta:
        model = IntegrationClient
        fields = ["name", "description", "is_active", "scopes"]

    def clean_scopes(self) -> list[str]:
        return services.checked_scopes(self.cleaned_data["scopes"])


@admin.register(IntegrationClient)
class IntegrationClientAdmin(admin.ModelAdmin[IntegrationClient]):
    form = IntegrationClientForm
    list_display = ["name", "is_active", "scope_list", "created_at"]
    fields = ["name", "description", "is_active", "scopes", "user"]
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
        created = services.create_integration_client(
            name=obj.name, description=obj.description, scopes=obj.scopes
        )
        obj.pk, obj.user = created.pk, created.user

    @admin.display(description="scopes")
    def scope_list(self, obj: IntegrationClient) -> str:
        return ", ".join(obj.scopes) or "none"

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


# Order sequences and recurring orders (a module of their own to keep this one readable).
import orders.admin_schedules  # noqa: E402, F401
