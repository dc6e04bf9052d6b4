"""Chargers, charging policies, charge sessions (the charging jobs), battery history and the
learned consumption model of each vehicle."""

from django.db import models

OPEN_SESSION_STATUSES = ["QUEUED", "ASSIGNED", "DRIVING", "CHARGING", "STOPPING"]
# A session holds its charging point from assignment until the vehicle leaves the charger.
BOOKED_STATUSES = ["ASSIGNED", "DRIVING", "CHARGING", "STOPPING"]


class Charger(models.Model):
    """A charge station with `capacity` charging points (its interaction nodes, in order; a
    station with one node and capacity > 1 shares that node, e.g. a multi-plug bay).
    No compatible types means every vehicle type may charge here."""

    station = models.OneToOneField("maps.Station", on_delete=models.CASCADE, related_name="charger")
    capacity = models.PositiveSmallIntegerField(default=1, help_text="charging points")
    vehicle_types = models.ManyToManyField(
        "maps.VehicleType", blank=True, help_text="empty: every vehicle type"
    )
    is_active = models.BooleanField(default=True)

    class Meta:
        ordering = ["station__station_id"]
        constraints = [
            models.CheckConstraint(condition=models.Q(capacity__gte=1), name="charger_capacity"),
        ]

    def __str__(self) -> str:
        return f"charger {self.station}"


class ChargingPolicy(models.Model):
    """Charge levels (percent) for a vehicle type; the one without a type is the default.

    critical < needs_charge <= sufficient <= charge_until <= full. Below `needs_charge` a vehicle
    takes no new work and is sent to charge; below `critical` it is sent first. A charging
    vehicle goes back to work once it has `sufficient` and work waits, else it charges until
    `charge_until`. Idle vehicles below `opportunity_below` charge when a point is free.
    `shift_reserve_hours` raises the working minimum to what the vehicle's learned
    consumption needs for that many hours above critical (shift-aware minimum).
    """

    vehicle_type = models.OneToOneField(
        "maps.VehicleType",
        null=True,
        blank=True,
        on_delete=models.CASCADE,
        related_name="charging_policy",
    )
    critical = models.FloatField(default=15.0)
    needs_charge = models.FloatField(default=30.0)
    sufficient = models.FloatField(default=60.0)
    charge_until = models.FloatField(default=90.0)
    full = models.FloatField(default=98.0)
    opportunity_charging = models.BooleanField(default=True)
    opportunity_below = models.FloatField(default=80.0)
    shift_reserve_hours = models.FloatField(default=0.0)

    class Meta:
        verbose_name_plural = "charging policies"
        constraints = [
            models.CheckConstraint(
                condition=models.Q(critical__gte=0)
                & models.Q(critical__lt=models.F("needs_charge"))
                & models.Q(needs_charge__lte=models.F("sufficient"))
                & models.Q(sufficient__lte=models.F("charge_until"))
                & models.Q(charge_until__lte=models.F("full"))
                & models.Q(full__lte=100),
                name="charging_policy_levels_ordered",
            ),
            models.UniqueConstraint(
                fields=["vehicle_type"],
                nulls_distinct=False,
                name="one_charging_policy_per_type",
            ),
        ]

    def __str__(self) -> str:
        return f"charging policy {self.vehicle_type or 'default'}"


class ChargeSession(models.Model):
    """One charging job: queued for a charger, assigned a point (with the route there), driven
    by `control` as a VDA 5050 order ending in `startCharging`, charging, stopped
    (`stopCharging`) and done once the vehicle left the point."""

    class Status(models.TextChoices):
        QUEUED = "QUEUED", "queued"
        ASSIGNED = "ASSIGNED", "assigned"
        DRIVING = "DRIVING", "driving to the charger"
        CHARGING = "CHARGING", "charging"
        STOPPING = "STOPPING", "charged, leaving"
        DONE = "DONE", "done"
        FAILED = "FAILED", "failed"
        CANCELLED = "CANCELLED", "cancelled"

    class Reason(models.TextChoices):
        CRITICAL = "CRITICAL", "critical level"
        LOW = "LOW", "needs charge"
        OPPORTUNITY = "OPPORTUNITY", "opportunity charging"
        MANUAL = "MANUAL", "sent by staff"

    vehicle = models.ForeignKey(
        "robots.Vehicle", on_delete=models.CASCADE, related_name="charge_sessions"
    )
    charger = models.ForeignKey(
        Charger, null=True, blank=True, on_delete=models.SET_NULL, related_name="sessions"
    )
    point = models.PositiveSmallIntegerField(null=True, blank=True)
    wanted_station = models.CharField(max_length=100, blank=True, help_text="staff's choice")
    status = models.CharField(
        max_length=10, choices=Status.choices, default=Status.QUEUED, db_index=True
    )
    reason = models.CharField(max_length=12, choices=Reason.choices)
    route = models.JSONField(default=list, blank=True)
    vda_order_id = models.CharField(max_length=100, blank=True)
    command_id = models.BigIntegerField(null=True, blank=True)
    start_charge = models.FloatField(null=True, blank=True)
    end_charge = models.FloatField(null=True, blank=True)
    note = models.CharField(max_length=200, blank=True)
    created_at = models.DateTimeField(auto_now_add=True)
    started_at = models.DateTimeField(null=True, blank=True)
    ended_at = models.DateTimeField(null=True, blank=True)

    class Meta:
        ordering = ["-created_at", "-pk"]
        constraints = [
            # No two vehicles are ever sent to one charging point: the database refuses it.
            models.UniqueConstraint(
                fields=["charger", "point"],
                condition=models.Q(status__in=BOOKED_STATUSES),
                name="one_vehicle_per_charging_point",
            ),
            models.UniqueConstraint(
                fields=["vehicle"],
                condition=models.Q(status__in=OPEN_SESSION_STATUSES),
                name="one_open_charge_session_per_vehicle",
            ),
        ]

    def __str__(self) -> str:
        return f"CS-{self.pk} {self.vehicle_id} ({self.status})"


class VehicleEnergy(models.Model):
    """Per vehicle: the learned consumption model, charge cycles and the health trend.

    `drain_per_metre` (% per metre driven) and `drain_per_hour` (% per hour standing, which
    covers actions and idling) are exponentially weighted averages of observed drops.
    `baseline_per_metre` is the first stable estimate: health = baseline / current.
    """

    vehicle = models.OneToOneField(
        "robots.Vehicle", on_delete=models.CASCADE, related_name="energy"
    )
    drain_per_metre = models.FloatField(null=True, blank=True)
    drain_per_hour = models.FloatField(null=True, blank=True)
    baseline_per_metre = models.FloatField(null=True, blank=True)
    metres_observed = models.FloatField(default=0.0)
    charge_cycles = models.FloatField(default=0.0, help_text="charged percent / 100")
    low_since = models.DateTimeField(null=True, blank=True)
    critical_since = models.DateTimeField(null=True, blank=True)
    updated_at = models.DateTimeField(auto_now=True)

    class Meta:
        verbose_name_plural = "vehicle energy"

    def __str__(self) -> str:
        return f"energy of {self.vehicle_id}"

    @property
    def health(self) -> float | None:
        """Percent of the first learned efficiency (100 = as new)."""
        if not (self.baseline_per_metre and self.drain_per_metre):
            return None
        return round(100.0 * self.baseline_per_metre / self.drain_per_metre, 1)


class BatterySample(models.Model):
    """A sampled battery reading (on a 1 % change, a charging switch, or every 5 minutes)."""

    vehicle = models.ForeignKey(
        "robots.Vehicle", on_delete=models.CASCADE, related_name="battery_samples"
    )
    at = models.DateTimeField(db_index=True)
    charge = models.FloatField()
    charging = models.BooleanField(default=False)
    drain_per_metre = models.FloatField(null=True, blank=True, help_text="model at that time")

    class Meta:
        ordering = ["vehicle", "-at"]
        indexes = [models.Index(fields=["vehicle", "-at"], name="battery_sample_recent")]

    def __str__(self) -> str:
        return f"{self.vehicle_id} {self.at:%Y-%m-%d %H:%M} {self.charge:.0f}%"


class BatteryAlert(models.Model):
    """A low or critical battery episode (the alerts app, issue 8, can take these over)."""

    class Level(models.TextChoices):
        LOW = "LOW", "needs charge"
        CRITICAL = "CRITICAL", "critical"

    vehicle = models.ForeignKey(
        "robots.Vehicle", on_delete=models.CASCADE, related_name="battery_alerts"
    )
    level = models.CharField(max_length=10, choices=Level.choices)
    charge = models.FloatField()
    raised_at = models.DateTimeField()
    resolved_at = models.DateTimeField(null=True, blank=True)

    class Meta:
        ordering = ["-raised_at"]
        constraints = [
            models.UniqueConstraint(
                fields=["vehicle", "level"],
                condition=models.Q(resolved_at__isnull=True),
                name="one_open_battery_alert_per_level",
            ),
        ]

    def __str__(self) -> str:
        return f"{self.level} battery {self.vehicle_id} at {self.charge:.0f}%"
