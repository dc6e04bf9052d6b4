"""Alert records, escalation rules and the notifications sent for them (issue 8)."""

from django.conf import settings
from django.db import models
from django.db.models import Q


class Severity(models.TextChoices):
    """How urgent an alert is; ordered, so escalation rules can say "at least URGENT".

    The names follow VDA 5050 3.0 (WARNING, URGENT, CRITICAL, FATAL) plus INFO; 2.x errors only
    know WARNING and FATAL and map onto those two.
    """

    INFO = "INFO", "info"
    WARNING = "WARNING", "warning"
    URGENT = "URGENT", "urgent"
    CRITICAL = "CRITICAL", "critical"
    FATAL = "FATAL", "fatal"


SEVERITY_RANK = {s.value: i for i, s in enumerate(Severity)}


class Source(models.TextChoices):
    """What kind of cause raised an alert (for filters, counts and reports)."""

    VDA_ERROR = "VDA_ERROR", "vehicle error (VDA 5050)"
    CONNECTION = "CONNECTION", "connection broken"
    STATE_TIMEOUT = "STATE_TIMEOUT", "state timeout"
    BATTERY = "BATTERY", "low battery"
    NO_PROGRESS = "NO_PROGRESS", "no progress"
    ORDER_FAILED = "ORDER_FAILED", "order failed"
    ORDER_LATE = "ORDER_LATE", "order late"
    MAINTENANCE = "MAINTENANCE", "maintenance due"
    INVENTORY = "INVENTORY", "inventory discrepancy"
    PROTOCOL = "PROTOCOL", "protocol violation"
    OTHER = "OTHER", "other"


class Alert(models.Model):
    """Something a person must look at, raised by a *cause* and kept until it is resolved.

    `cause` is a stable key naming what raised the alert (e.g. ``vda:12:noRouteError``); at most
    one alert per cause is open (not RESOLVED) at a time, enforced by a partial unique index, so
    a cause that persists bumps `occurrences`/`last_seen_at` instead of opening duplicates. When
    the cause clears, the service resolves the alert automatically (`auto_resolved`).
    """

    class Status(models.TextChoices):
        OPEN = "OPEN", "open"
        ACKNOWLEDGED = "ACKNOWLEDGED", "acknowledged"
        RESOLVED = "RESOLVED", "resolved"

    cause = models.CharField(max_length=200, db_index=True)
    source = models.CharField(max_length=20, choices=Source.choices, default=Source.OTHER)
    severity = models.CharField(max_length=10, choices=Severity.choices, default=Severity.WARNING)
    status = models.CharField(max_length=15, choices=Status.choices, default=Status.OPEN)
    vehicle = models.ForeignKey(
        "robots.Vehicle", null=True, blank=True, on_delete=models.SET_NULL, related_name="alerts"
    )
    # A plain reference (external or internal order id): alerts sit below orders and never
    # import them.
    order_ref = models.CharField(max_length=100, blank=True, db_index=True)
    message = models.TextField()
    details = models.JSONField(default=dict, blank=True)
    occurrences = models.PositiveIntegerField(default=1)
    raised_at = models.DateTimeField(auto_now_add=True, db_index=True)
    last_seen_at = models.DateTimeField(auto_now_add=True)
    acknowledged_at = models.DateTimeField(null=True, blank=True)
    acknowledged_by = models.ForeignKey(
        settings.AUTH_USER_MODEL,
        null=True,
        blank=True,
        on_delete=models.SET_NULL,
        related_name="+",
    )
    acknowledge_comment = models.TextField(blank=True)
    resolved_at = models.DateTimeField(null=True, blank=True)
    resolved_by = models.ForeignKey(
        settings.AUTH_USER_MODEL,
        null=True,
        blank=True,
        on_delete=models.SET_NULL,
        related_name="+",
    )
    resolve_comment = models.TextField(blank=True)
    auto_resolved = models.BooleanField(default=False)

    class Meta:
        ordering = ["-raised_at", "-pk"]
        constraints = [
            models.UniqueConstraint(
                fields=["cause"],
                condition=~Q(status="RESOLVED"),
                name="alert_one_open_per_cause",
            ),
        ]
        indexes = [models.Index(fields=["status", "severity"], name="alert_status_severity")]

    def __str__(self) -> str:
        return f"{self.severity} {self.cause}: {self.message[:60]}"

    @property
    def is_open(self) -> bool:
        return self.status != self.Status.RESOLVED


class EscalationRule(models.Model):
    """Notify someone when an alert of at least `min_severity` stays unacknowledged too long.

    Each rule fires at most once per alert (see `AlertNotification`); a rule may send an email
    (Django's email backend), post a webhook, or both.
    """

    name = models.CharField(max_length=100)
    active = models.BooleanField(default=True)
    min_severity = models.CharField(
        max_length=10, choices=Severity.choices, default=Severity.URGENT
    )
    source = models.CharField(
        max_length=20, choices=Source.choices, blank=True, help_text="empty: every source"
    )
    after_minutes = models.PositiveIntegerField(default=10)
    email_to = models.TextField(blank=True, help_text="addresses, separated by commas")
    webhook_url = models.URLField(blank=True)

    class Meta:
        ordering = ["after_minutes", "name"]

    def __str__(self) -> str:
        return f"{self.name} (≥{self.min_severity}, {self.after_minutes} min)"

    def recipients(self) -> list[str]:
        return [a.strip() for a in self.email_to.split(",") if a.strip()]


class AlertNotification(models.Model):
    """One escalation of one alert by one rule: what was sent and whether it got through."""

    alert = models.ForeignKey(Alert, on_delete=models.CASCADE, related_name="notifications")
    rule = models.ForeignKey(EscalationRule, on_delete=models.CASCADE, related_name="+")
    sent_at = models.DateTimeField(auto_now_add=True)
    email_sent = models.BooleanField(default=False)
    webhook_status = models.PositiveIntegerField(null=True, blank=True)
    error = models.TextField(blank=True)

    class Meta:
        ordering = ["-sent_at"]
        constraints = [
            models.UniqueConstraint(fields=["alert", "rule"], name="alert_notification_once"),
        ]

    def __str__(self) -> str:
        return f"{self.rule_id} → alert {self.alert_id}"
