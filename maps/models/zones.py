"""Zones: polygons on a map that close, slow down, direct or price the traffic inside them."""

from typing import Any

from django.core.exceptions import ValidationError
from django.db import models

from maps import zoning


class Zone(models.Model):
    """A polygon on a map with a type (VDA 5050 3.0 zone types plus our own; see `maps.zoning`).

    `vertices` are [{x, y}] in metres, stored counter-clockwise as VDA 5050 asks. Which of the
    other fields count depends on the type: `max_speed` (SPEED_LIMIT), `direction` and
    `limitation` (DIRECTED, BIDIRECTED), `penalty_factor` (PENALTY), `priority_factor` (PRIORITY),
    `release_loss_behavior` (RELEASE), the three action lists (ACTION), `vehicle_types` (the
    types RESTRICTED lets in). A disabled zone is kept but does nothing.
    """

    class Type(models.TextChoices):
        BLOCKED = zoning.BLOCKED, "blocked"
        RESTRICTED = zoning.RESTRICTED, "restricted (listed vehicle types only)"
        SPEED_LIMIT = zoning.SPEED_LIMIT, "speed limit"
        DIRECTED = zoning.DIRECTED, "one-way (directed)"
        BIDIRECTED = zoning.BIDIRECTED, "bidirectional"
        NO_STOPPING = zoning.NO_STOPPING, "no stopping"
        PARKING = zoning.PARKING, "parking area"
        CHARGING = zoning.CHARGING, "charging area"
        LINE_GUIDED = zoning.LINE_GUIDED, "line guided"
        RELEASE = zoning.RELEASE, "release (access on request)"
        COORDINATED_REPLANNING = zoning.COORDINATED_REPLANNING, "coordinated replanning"
        ACTION = zoning.ACTION, "action"
        PRIORITY = zoning.PRIORITY, "priority"
        PENALTY = zoning.PENALTY, "penalty"

    class Limitation(models.TextChoices):
        SOFT = "SOFT", "soft (avoid other directions)"
        RESTRICTED = "RESTRICTED", "restricted (never against the direction)"
        STRICT = "STRICT", "strict (only the direction)"

    class ReleaseLoss(models.TextChoices):
        STOP = "STOP", "stop"
        CONTINUE = "CONTINUE", "continue"
        EVACUATE = "EVACUATE", "evacuate"

    map = models.ForeignKey("maps.Map", on_delete=models.CASCADE, related_name="zones")
    zone_id = models.CharField(max_length=100)
    name = models.CharField(max_length=200, blank=True, help_text="VDA 5050 zoneDescriptor")
    description = models.TextField(blank=True)
    zone_type = models.CharField(max_length=30, choices=Type.choices)
    enabled = models.BooleanField(default=True)
    vertices = models.JSONField(default=list, help_text="[{x, y}] in metres, at least three")
    max_speed = models.FloatField(null=True, blank=True, help_text="m/s (speed limit)")
    direction = models.FloatField(
        null=True, blank=True, help_text="rad, direction of travel (one-way, bidirectional)"
    )
    limitation = models.CharField(
        max_length=10, choices=Limitation.choices, blank=True, help_text="one-way, bidirectional"
    )
    penalty_factor = models.FloatField(null=True, blank=True, help_text="0 to 1 (penalty)")
    priority_factor = models.FloatField(null=True, blank=True, help_text="0 to 1 (priority)")
    release_loss_behavior = models.CharField(
        max_length=10, choices=ReleaseLoss.choices, blank=True, help_text="release"
    )
    entry_actions = models.JSONField(default=list, blank=True, help_text="action zone")
    during_actions = models.JSONField(default=list, blank=True, help_text="action zone")
    exit_actions = models.JSONField(default=list, blank=True, help_text="action zone")
    vehicle_types = models.ManyToManyField(
        "maps.VehicleType",
        blank=True,
        related_name="+",
        help_text="restricted: the vehicle types allowed in (none: closed to all)",
    )
    created_at = models.DateTimeField(auto_now_add=True)
    updated_at = models.DateTimeField(auto_now=True)

    class Meta:
        ordering = ["map", "zone_id"]
        constraints = [
            models.UniqueConstraint(fields=["map", "zone_id"], name="zone_id_unique_per_map"),
            models.CheckConstraint(
                condition=models.Q(max_speed__isnull=True) | models.Q(max_speed__gt=0),
                name="zone_max_speed_positive",
            ),
            models.CheckConstraint(
                condition=models.Q(penalty_factor__isnull=True)
                | models.Q(penalty_factor__gte=0, penalty_factor__lte=1),
                name="zone_penalty_factor_0_to_1",
            ),
            models.CheckConstraint(
                condition=models.Q(priority_factor__isnull=True)
                | models.Q(priority_factor__gte=0, priority_factor__lte=1),
                name="zone_priority_factor_0_to_1",
            ),
        ]

    def __str__(self) -> str:
        return self.name or self.zone_id

    def clean(self) -> None:
        """The type's required fields and a simple polygon (the admin's form calls this)."""
        errors: dict[str, list[str]] = {}
        for field, message in zoning.zone_problems(**self.rule_fields()):
            errors.setdefault(field, []).append(message)
        if errors:
            raise ValidationError(errors)

    def rule_fields(self) -> dict[str, Any]:
        """The fields `maps.zoning.zone_problems` checks."""
        return {field: getattr(self, field) for field in zoning.ZONE_RULE_FIELDS}
