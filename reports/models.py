"""Aggregated tables the report pages read, kept up to date by Celery (reports.tasks).

Report pages never scan raw history: order outcomes are rolled up per vehicle and hour when the
orders end, vehicle time is sampled into the same hourly rows, and distributions are kept as
narrow per-day counts. Every report is one grouped query per table: 30 days of 100 vehicles are
72,000 hourly rows, which the database sums in milliseconds.
"""

from django.db import models

# Upper bounds (seconds) of the lead-time histogram buckets; the last bucket is open-ended.
LEAD_TIME_BUCKETS = (15, 30, 60, 120, 300, 600, 900, 1800, 3600, 7200)
LEAD_TIME_STAGES = ("waiting", "approach", "execution", "total")


class VehicleHour(models.Model):
    """What one vehicle did in one hour: orders ended, time by state, distance and energy.

    Order figures are added once per order when it ends (reports.services.roll_up_orders); the
    time, distance and energy columns grow with each sample of the vehicles' live state.
    `vehicle` is None for orders that ended without a vehicle.
    """

    hour = models.DateTimeField(help_text="start of the hour (UTC)")
    vehicle = models.ForeignKey(
        "robots.Vehicle", null=True, blank=True, on_delete=models.CASCADE, related_name="+"
    )
    finished = models.PositiveIntegerField(default=0)
    failed = models.PositiveIntegerField(default=0)
    cancelled = models.PositiveIntegerField(default=0)
    with_deadline = models.PositiveIntegerField(default=0, help_text="finished with a deadline")
    on_time = models.PositiveIntegerField(default=0, help_text="finished by their deadline")
    busy_s = models.FloatField(default=0)
    idle_s = models.FloatField(default=0)
    charging_s = models.FloatField(default=0)
    error_s = models.FloatField(default=0)
    offline_s = models.FloatField(default=0)
    distance_m = models.FloatField(default=0)
    energy_pct = models.FloatField(default=0, help_text="battery percentage points used")

    class Meta:
        ordering = ["hour", "vehicle"]
        constraints = [
            models.UniqueConstraint(fields=["hour", "vehicle"], name="vehicle_hour_unique"),
        ]
        indexes = [models.Index(fields=["vehicle", "hour"])]

    def __str__(self) -> str:
        return f"{self.hour:%Y-%m-%d %H}:00 vehicle {self.vehicle_id}"


class LeadTimeCount(models.Model):
    """How many orders finished on a day with a lead-time stage in one histogram bucket.

    One narrow row per (day, vehicle, stage, bucket) lets the database add up the distribution
    of any range in one grouped query. `seconds` is the sum of those orders' stage durations.
    """

    day = models.DateField(help_text="local date (TIME_ZONE)")
    vehicle = models.ForeignKey(
        "robots.Vehicle", null=True, blank=True, on_delete=models.CASCADE, related_name="+"
    )
    stage = models.CharField(max_length=20)
    bucket = models.PositiveSmallIntegerField(help_text="index into LEAD_TIME_BUCKETS")
    count = models.PositiveIntegerField(default=0)
    seconds = models.FloatField(default=0)

    class Meta:
        ordering = ["day", "vehicle", "stage", "bucket"]
        constraints = [
            models.UniqueConstraint(
                fields=["day", "vehicle", "stage", "bucket"], name="lead_time_count_unique"
            ),
        ]

    def __str__(self) -> str:
        return f"{self.day} vehicle {self.vehicle_id} {self.stage}[{self.bucket}] = {self.count}"


class ErrorCount(models.Model):
    """How often an error type appeared on a vehicle on a day (seen by the sampler)."""

    day = models.DateField(help_text="local date (TIME_ZONE)")
    vehicle = models.ForeignKey(
        "robots.Vehicle", null=True, blank=True, on_delete=models.CASCADE, related_name="+"
    )
    error_type = models.CharField(max_length=200)
    count = models.PositiveIntegerField(default=0)

    class Meta:
        ordering = ["day", "vehicle", "error_type"]
        constraints = [
            models.UniqueConstraint(
                fields=["day", "vehicle", "error_type"], name="error_count_unique"
            ),
        ]

    def __str__(self) -> str:
        return f"{self.day} vehicle {self.vehicle_id} {self.error_type} × {self.count}"


class SamplerMark(models.Model):
    """Where the sampler last looked at each vehicle, to turn samples into durations."""

    vehicle = models.OneToOneField("robots.Vehicle", on_delete=models.CASCADE, related_name="+")
    at = models.DateTimeField()
    x = models.FloatField(null=True)
    y = models.FloatField(null=True)
    map_id = models.CharField(max_length=100, blank=True)
    battery_charge = models.FloatField(null=True)
    error_types = models.JSONField(default=list)

    def __str__(self) -> str:
        return f"vehicle {self.vehicle_id} at {self.at}"


class RollupMark(models.Model):
    """How far the order roll-up has read (orders updated up to `at`); one row."""

    at = models.DateTimeField()

    def __str__(self) -> str:
        return f"rolled up to {self.at}"


# Upper bounds (seconds) of the traffic-wait histogram buckets; the last bucket is open-ended.
WAIT_BUCKETS = (2, 5, 10, 20, 30, 60, 120, 300, 600)


class TrafficWait(models.Model):
    """One wait of a vehicle held by traffic management at its decision point: where, from when,
    how long and for whom. Written by `control`'s flush when the wait ends (reports.waits);
    the Celery roll-up adds it to the wait tables below, which the report page reads."""

    vehicle = models.ForeignKey("robots.Vehicle", on_delete=models.CASCADE, related_name="+")
    map_id = models.CharField(max_length=100, blank=True)
    node_id = models.CharField(max_length=100, blank=True, help_text="the node it waited at")
    x = models.FloatField(null=True, blank=True)
    y = models.FloatField(null=True, blank=True)
    started_at = models.DateTimeField()
    seconds = models.FloatField()
    waited_for = models.JSONField(default=list, help_text="serial numbers of the vehicles")

    class Meta:
        ordering = ["started_at"]
        indexes = [models.Index(fields=["vehicle", "started_at"])]

    def __str__(self) -> str:
        return f"vehicle {self.vehicle_id} waited {self.seconds:.0f} s at {self.node_id}"


class WaitHourCount(models.Model):
    """Traffic waits of the whole fleet that began in one hour, per histogram bucket."""

    hour = models.DateTimeField(help_text="start of the hour (UTC)")
    bucket = models.PositiveSmallIntegerField(help_text="index into WAIT_BUCKETS")
    count = models.PositiveIntegerField(default=0)
    seconds = models.FloatField(default=0)

    class Meta:
        ordering = ["hour", "bucket"]
        constraints = [
            models.UniqueConstraint(fields=["hour", "bucket"], name="wait_hour_count_unique")
        ]

    def __str__(self) -> str:
        return f"{self.hour:%Y-%m-%d %H}:00 waits[{self.bucket}] = {self.count}"


class WaitDayCount(models.Model):
    """Traffic waits of one vehicle that began on a day, per histogram bucket."""

    day = models.DateField(help_text="local date (TIME_ZONE)")
    vehicle = models.ForeignKey("robots.Vehicle", on_delete=models.CASCADE, related_name="+")
    bucket = models.PositiveSmallIntegerField(help_text="index into WAIT_BUCKETS")
    count = models.PositiveIntegerField(default=0)
    seconds = models.FloatField(default=0)

    class Meta:
        ordering = ["day", "vehicle", "bucket"]
        constraints = [
            models.UniqueConstraint(
                fields=["day", "vehicle", "bucket"], name="wait_day_count_unique"
            )
        ]

    def __str__(self) -> str:
        return f"{self.day} vehicle {self.vehicle_id} waits[{self.bucket}] = {self.count}"


class WaitNodeDay(models.Model):
    """Traffic waits at one node on a day: the heatmap's figures. One row per vehicle, plus one
    with `vehicle` None for the whole fleet, which the unfiltered heatmap reads (a few rows a
    day per node instead of one per vehicle)."""

    day = models.DateField(help_text="local date (TIME_ZONE)")
    vehicle = models.ForeignKey(
        "robots.Vehicle", null=True, blank=True, on_delete=models.CASCADE, related_name="+"
    )
    map_id = models.CharField(max_length=100)
    node_id = models.CharField(max_length=100)
    count = models.PositiveIntegerField(default=0)
    seconds = models.FloatField(default=0)

    class Meta:
        ordering = ["day", "vehicle", "map_id", "node_id"]
        constraints = [
            models.UniqueConstraint(
                fields=["day", "vehicle", "map_id", "node_id"], name="wait_node_day_unique"
            )
        ]

    def __str__(self) -> str:
        return (
            f"{self.day} vehicle {self.vehicle_id} {self.map_id}/{self.node_id}: {self.seconds} s"
        )


class WaitMark(models.Model):
    """How far the traffic-wait roll-up has read (TrafficWait ids up to `last_id`); one row."""

    last_id = models.BigIntegerField(default=0)

    def __str__(self) -> str:
        return f"waits rolled up to id {self.last_id}"
