"""Commands to vehicles requested over the API and queued for `control`."""

from django.conf import settings
from django.db import models


class VehicleCommand(models.Model):
    """A request to a vehicle (pause, resume, go charging or parking, an instant action), kept as
    an audit record. It is queued for `control`, which publishes what the vehicle needs; the
    vehicle's state then tells the outcome (`paused`, `charging`, the action's state)."""

    class Kind(models.TextChoices):
        PAUSE = "vehicle.pause", "pause"
        RESUME = "vehicle.resume", "resume"
        CHARGE = "vehicle.charge", "send to charge"
        PARK = "vehicle.park", "send to park"
        INSTANT_ACTION = "vehicle.instant_action", "instant action"

    vehicle = models.ForeignKey("robots.Vehicle", on_delete=models.CASCADE, related_name="commands")
    kind = models.CharField(max_length=30, choices=Kind.choices)
    parameters = models.JSONField(default=dict, blank=True)
    requested_by = models.ForeignKey(
        settings.AUTH_USER_MODEL, null=True, blank=True, on_delete=models.SET_NULL, related_name="+"
    )

    class Status(models.TextChoices):
        QUEUED = "QUEUED", "queued"  # waiting for control
        SENT = "SENT", "sent"  # control published the instant action
        REFUSED = "REFUSED", "refused"  # control did not send it; `result` says why
        RUNNING = "RUNNING", "running"
        FINISHED = "FINISHED", "finished"
        FAILED = "FAILED", "failed"

    status = models.CharField(max_length=10, choices=Status.choices, default=Status.QUEUED)
    result = models.TextField(blank=True, help_text="why it was refused or failed")
    action_id = models.CharField(max_length=100, blank=True, help_text="VDA 5050 actionId")
    created_at = models.DateTimeField(auto_now_add=True)
    updated_at = models.DateTimeField(auto_now=True)

    class Meta:
        ordering = ["-created_at", "-pk"]

    def __str__(self) -> str:
        return f"{self.get_kind_display()} → {self.vehicle}"
