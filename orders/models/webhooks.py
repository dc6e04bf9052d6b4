"""Webhooks: what integration clients subscribe to, and every delivery and attempt."""

import uuid

from django.core.serializers.json import DjangoJSONEncoder
from django.db import models

from orders.models.integrations import IntegrationClient

EVENT_TYPES = [
    "order.created",
    "order.assigned",
    "order.started",
    "order.step_reached",
    "order.finished",
    "order.failed",
    "order.requeued",
    "order.updated",
    "order.cancel_requested",
    "order.cancelled",
    "vehicle.command_queued",
    "vehicle.connection_changed",
    "vehicle.mode_changed",
    "vehicle.error",
    "vehicle.order_assigned",
    "vehicle.order_finished",
    "ping",
]


class WebhookSubscription(models.Model):
    """An integration client's endpoint for events (`events`: types such as `order.finished`,
    `order.*` for a whole family, or `*`). Bodies are signed with `secret` (HMAC-SHA256)."""

    client = models.ForeignKey(
        IntegrationClient, on_delete=models.CASCADE, related_name="webhook_subscriptions"
    )
    url = models.URLField(max_length=500)
    events = models.JSONField(default=list, help_text='event types, "order.*" or "*"')
    secret = models.CharField(max_length=100)
    description = models.CharField(max_length=200, blank=True)
    own_orders_only = models.BooleanField(
        default=False, help_text="order events only for orders this client created"
    )
    is_active = models.BooleanField(default=True)
    created_at = models.DateTimeField(auto_now_add=True)

    class Meta:
        ordering = ["client", "pk"]

    def __str__(self) -> str:
        return f"{self.client} → {self.url}"

    def wants(self, event_type: str) -> bool:
        """Whether this subscription asked for `event_type`."""
        family = event_type.split(".", 1)[0] + ".*"
        return any(wanted in {"*", event_type, family} for wanted in self.events or [])


class WebhookDelivery(models.Model):
    """One event for one subscription: the body to send and where its retries stand.

    Rows are written in the same transaction as the change they report (an outbox), so a lost
    Celery message only delays a delivery: the periodic sweep sends every PENDING delivery whose
    `next_attempt_at` has passed.
    """

    class Status(models.TextChoices):
        PENDING = "PENDING", "pending"
        DELIVERED = "DELIVERED", "delivered"
        FAILED = "FAILED", "failed"

    subscription = models.ForeignKey(
        WebhookSubscription, on_delete=models.CASCADE, related_name="deliveries"
    )
    event_id = models.UUIDField(default=uuid.uuid4, help_text="the same for every subscription")
    event_type = models.CharField(max_length=50)
    payload = models.JSONField(encoder=DjangoJSONEncoder)
    status = models.CharField(max_length=10, choices=Status.choices, default=Status.PENDING)
    attempts = models.PositiveSmallIntegerField(default=0)
    next_attempt_at = models.DateTimeField()
    created_at = models.DateTimeField(auto_now_add=True)
    delivered_at = models.DateTimeField(null=True, blank=True)

    class Meta:
        ordering = ["-created_at", "-pk"]
        indexes = [models.Index(fields=["status", "next_attempt_at"], name="webhook_due_idx")]

    def __str__(self) -> str:
        return f"{self.event_type} → {self.subscription.url} ({self.status})"


class WebhookAttempt(models.Model):
    """One HTTP attempt of a delivery: the answer's status code and the start of its body, or the
    error when there was no answer (refused, timed out)."""

    delivery = models.ForeignKey(WebhookDelivery, on_delete=models.CASCADE, related_name="log")
    at = models.DateTimeField(auto_now_add=True)
    status_code = models.PositiveSmallIntegerField(null=True, blank=True)
    response_excerpt = models.CharField(max_length=500, blank=True)
    error = models.CharField(max_length=300, blank=True)
    duration_ms = models.PositiveIntegerField(default=0)

    class Meta:
        ordering = ["delivery", "at", "pk"]

    def __str__(self) -> str:
        return f"{self.delivery_id} {self.status_code or self.error}"

    @property
    def succeeded(self) -> bool:
        return self.status_code is not None and 200 <= self.status_code < 300
