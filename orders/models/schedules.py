"""Recurring transport orders that staff set up: a template and a schedule."""

from django.conf import settings
from django.db import models

from orders.models.transport import TransportOrder


def _weekdays() -> list[int]:
    return [0, 1, 2, 3, 4]


class RecurringOrder(models.Model):
    """Create a transport order from `steps` every `interval_minutes` on `weekdays`
    (0 = Monday) between `window_start` and `window_end` (local time, end exclusive).

    Slots are counted from `window_start` each day: with 06:00–22:00 every 15 minutes they are
    06:00, 06:15, … 21:45. Only the latest due slot creates an order (a beat that was down for
    an hour does not flood the fleet with missed ones), and never a slot from before the
    schedule existed. `steps` lists `{"station", "operation", "action_type", "parameters"}`
    as the API takes them, on `map`.
    """

    name = models.CharField(max_length=100)
    is_active = models.BooleanField(default=True)
    map = models.ForeignKey("maps.Map", on_delete=models.CASCADE, related_name="+")
    steps = models.JSONField(help_text='[{"station": "PICK-1", "operation": "PICK"}, …]')
    priority = models.IntegerField(default=0)
    load_type = models.CharField(max_length=100, blank=True, default="EPAL")
    vehicle_type = models.ForeignKey(
        "maps.VehicleType", null=True, blank=True, on_delete=models.PROTECT, related_name="+"
    )
    interval_minutes = models.PositiveIntegerField(default=15)
    weekdays = models.JSONField(default=_weekdays, help_text="0 = Monday … 6 = Sunday")
    window_start = models.TimeField(default="00:00")
    window_end = models.TimeField(default="23:59:59", help_text="no slot at or after this time")
    created_by = models.ForeignKey(
        settings.AUTH_USER_MODEL, null=True, blank=True, on_delete=models.SET_NULL, related_name="+"
    )
    created_at = models.DateTimeField(auto_now_add=True)
    last_slot = models.DateTimeField(null=True, blank=True, help_text="latest slot created")

    class Meta:
        ordering = ["name", "pk"]
        constraints = [
            models.CheckConstraint(
                condition=models.Q(interval_minutes__gte=1), name="recurring_interval_positive"
            ),
            models.CheckConstraint(
                condition=models.Q(window_end__gt=models.F("window_start")),
                name="recurring_window_not_empty",
            ),
        ]

    def __str__(self) -> str:
        return self.name


class RecurringOrderRun(models.Model):
    """The order one slot of a schedule created. Unique per (schedule, slot), so two beats that
    overlap, or a task that runs twice, create each slot's order exactly once."""

    schedule = models.ForeignKey(RecurringOrder, on_delete=models.CASCADE, related_name="runs")
    slot = models.DateTimeField()
    order = models.ForeignKey(
        TransportOrder, null=True, blank=True, on_delete=models.SET_NULL, related_name="+"
    )
    error = models.CharField(max_length=300, blank=True)
    created_at = models.DateTimeField(auto_now_add=True)

    class Meta:
        ordering = ["-slot"]
        constraints = [
            models.UniqueConstraint(fields=["schedule", "slot"], name="recurring_slot_once")
        ]

    def __str__(self) -> str:
        return f"{self.schedule} @ {self.slot:%Y-%m-%d %H:%M}"
