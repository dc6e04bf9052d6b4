"""Integration clients (ERP/WMS), their API tokens and the idempotency keys of their requests."""

from django.conf import settings
from django.core.serializers.json import DjangoJSONEncoder
from django.db import models


class IntegrationClient(models.Model):
    """A system that talks to the fleet over the REST API (an ERP, a WMS, a line controller).

    Each client acts as its own Django user (`user`, created with the client and without a
    password), so orders record who created them and idempotency keys are scoped per client.
    It authenticates with one of its `tokens` and owns its webhook subscriptions; `scopes` say
    which endpoints its tokens may call.
    """

    name = models.CharField(max_length=100, unique=True)
    user = models.OneToOneField(
        settings.AUTH_USER_MODEL, on_delete=models.PROTECT, related_name="integration_client"
    )
    description = models.TextField(blank=True)
    is_active = models.BooleanField(default=True)
    scopes = models.JSONField(
        default=list,
        blank=True,
        help_text="API scopes its tokens carry (fleet.roles.API_SCOPES), e.g. orders:write",
    )
    created_at = models.DateTimeField(auto_now_add=True)

    class Meta:
        ordering = ["name"]

    def __str__(self) -> str:
        return self.name


class ApiToken(models.Model):
    """A bearer token of an integration client. Only a SHA-256 hash of the key is stored; the key
    itself is shown once when it is issued. `prefix` (the key's first characters) tells tokens
    apart in lists and logs."""

    client = models.ForeignKey(IntegrationClient, on_delete=models.CASCADE, related_name="tokens")
    key_hash = models.CharField(max_length=64, unique=True)
    prefix = models.CharField(max_length=12)
    created_at = models.DateTimeField(auto_now_add=True)
    expires_at = models.DateTimeField(null=True, blank=True)
    last_used_at = models.DateTimeField(null=True, blank=True)
    revoked_at = models.DateTimeField(null=True, blank=True)

    class Meta:
        ordering = ["client", "-created_at"]

    def __str__(self) -> str:
        return f"{self.client} {self.prefix}…"

    @property
    def scopes(self) -> list[str]:
        """What the token may do: its client's scopes (fleet.api_access checks them)."""
        return list(self.client.scopes)


class IdempotencyKey(models.Model):
    """The `Idempotency-Key` of a POST and what it produced, per user (= per client).

    A key is claimed IN_FLIGHT (committed at once, so concurrent retries see it) before the
    request runs, and COMPLETED with the response in the same transaction as the request's
    writes. A retry with the same key and body replays the stored response; the same key with
    another body is refused. A request that fails releases (deletes) its key.
    """

    class State(models.TextChoices):
        IN_FLIGHT = "IN_FLIGHT", "in flight"
        COMPLETED = "COMPLETED", "completed"

    user = models.ForeignKey(
        settings.AUTH_USER_MODEL, on_delete=models.CASCADE, related_name="idempotency_keys"
    )
    key = models.CharField(max_length=255)
    request_hash = models.CharField(max_length=64, help_text="SHA-256 of method, path and body")
    request_path = models.CharField(max_length=200)
    state = models.CharField(max_length=10, choices=State.choices, default=State.IN_FLIGHT)
    response_status = models.PositiveSmallIntegerField(null=True, blank=True)
    response_body = models.JSONField(null=True, blank=True, encoder=DjangoJSONEncoder)
    created_at = models.DateTimeField(auto_now_add=True, db_index=True)
    locked_at = models.DateTimeField(help_text="when the current attempt started")
    completed_at = models.DateTimeField(null=True, blank=True)

    class Meta:
        ordering = ["-created_at"]
        constraints = [
            models.UniqueConstraint(fields=["user", "key"], name="idempotency_key_unique_per_user"),
        ]

    def __str__(self) -> str:
        return f"{self.user_id}:{self.key} ({self.state})"
