"""Service plans, counters kept from vehicle state, work orders, availability, error history."""

from django.conf import settings
from django.db import models

OPEN_WORK = ["DUE", "OPEN", "IN_PROGRESS"]


class ServicePlan(models.Model):
    """Preventive maintenance for a vehicle type or one vehicle (neither: every vehicle).

    A work order is due when any interval since the last one is reached: operating hours,
    distance driven (km), charge cycles or calendar days. `takes_out_of_service`: the vehicle
    gets no work from the moment the order is due until it is done.
    """

    name = models.CharField(max_length=200)
    vehicle_type = models.ForeignKey(
        "maps.VehicleType", null=True, blank=True, on_delete=models.CASCADE, related_name="+"
    )
    vehicle = models.ForeignKey(
        "robots.Vehicle", null=True, blank=True, on_delete=models.CASCADE, related_name="+"
    )
    interval_hours = models.FloatField(null=True, blank=True, help_text="operating hours")
    interval_km = models.FloatField(null=True, blank=True, help_text="distance driven")
    interval_cycles = models.FloatField(null=True, blank=True, help_text="charge cycles")
    interval_days = models.PositiveIntegerField(null=True, blank=True, help_text="calendar days")
    grace_days = models.FloatField(default=1.0, help_text="overdue this long after due")
    takes_out_of_service = models.BooleanField(default=True)
    instructions = models.TextField(blank=True)
    is_active = models.BooleanField(default=True)

    class Meta:
        ordering = ["name"]
        constraints = [
            models.CheckConstraint(
                condition=models.Q(interval_hours__isnull=False)
                | models.Q(interval_km__isnull=False)
                | models.Q(interval_cycles__isnull=False)
                | models.Q(interval_days__isnull=False),
                name="service_plan_has_an_interval",
            ),
            models.CheckConstraint(
                condition=models.Q(vehicle__isnull=True) | models.Q(vehicle_type__isnull=True),
                name="service_plan_for_type_or_vehicle",
            ),
        ]

    def __str__(self) -> str:
        return self.name


class VehicleCounters(models.Model):
    """Counters kept from the vehicle's state by `control`'s flush (sampled, cheap), and
    whether staff took the vehicle out of service."""

    vehicle = models.OneToOneField(
        "robots.Vehicle", on_delete=models.CASCADE, related_name="service_counters"
    )
    operating_seconds = models.FloatField(default=0.0, help_text="online in an automatic mode")
    driving_seconds = models.FloatField(default=0.0)
    distance_m = models.FloatField(default=0.0)
    charge_cycles = models.FloatField(default=0.0)
    out_of_service = models.BooleanField(default=False)
    out_of_service_reason = models.CharField(max_length=200, blank=True)
    out_of_service_since = models.DateTimeField(null=True, blank=True)
    updated_at = models.DateTimeField(auto_now=True)

    class Meta:
        verbose_name_plural = "vehicle counters"

    def __str__(self) -> str:
        return f"counters of {self.vehicle_id}"

    @property
    def operating_hours(self) -> float:
        return self.operating_seconds / 3600.0

    @property
    def distance_km(self) -> float:
        return self.distance_m / 1000.0


class PlanBaseline(models.Model):
    """The counters of a vehicle when its plan was last serviced (or first applied)."""

    plan = models.ForeignKey(ServicePlan, on_delete=models.CASCADE, related_name="baselines")
    vehicle = models.ForeignKey("robots.Vehicle", on_delete=models.CASCADE, related_name="+")
    hours = models.FloatField(default=0.0)
    km = models.FloatField(default=0.0)
    cycles = models.FloatField(default=0.0)
    since = models.DateTimeField()

    class Meta:
        constraints = [
            models.UniqueConstraint(fields=["plan", "vehicle"], name="one_baseline_per_plan"),
        ]

    def __str__(self) -> str:
        return f"{self.plan_id}/{self.vehicle_id} since {self.since:%Y-%m-%d}"


class WorkOrder(models.Model):
    """A maintenance job on one vehicle: due (from a plan), open, in progress, done."""

    class Status(models.TextChoices):
        DUE = "DUE", "due"
        OPEN = "OPEN", "open"
        IN_PROGRESS = "IN_PROGRESS", "in progress"
        DONE = "DONE", "done"

    vehicle = models.ForeignKey(
        "robots.Vehicle", on_delete=models.CASCADE, related_name="work_orders"
    )
    plan = models.ForeignKey(
        ServicePlan, null=True, blank=True, on_delete=models.SET_NULL, related_name="work_orders"
    )
    title = models.CharField(max_length=200)
    status = models.CharField(
        max_length=12, choices=Status.choices, default=Status.OPEN, db_index=True
    )
    takes_out_of_service = models.BooleanField(default=True)
    trigger = models.CharField(max_length=200, blank=True, help_text="which interval fired")
    counters = models.JSONField(default=dict, blank=True, help_text="counters when created")
    notes = models.TextField(blank=True, help_text="technician notes")
    parts = models.JSONField(default=list, blank=True, help_text='[{"part": "", "qty": 1}]')
    technician = models.ForeignKey(
        settings.AUTH_USER_MODEL, null=True, blank=True, on_delete=models.SET_NULL, related_name="+"
    )
    due_at = models.DateTimeField()
    created_at = models.DateTimeField(auto_now_add=True)
    started_at = models.DateTimeField(null=True, blank=True)
    done_at = models.DateTimeField(null=True, blank=True)

    class Meta:
        ordering = ["-due_at", "-pk"]
        constraints = [
            # A plan fires once per vehicle until that work order is done.
            models.UniqueConstraint(
                fields=["plan", "vehicle"],
                condition=models.Q(status__in=OPEN_WORK),
                name="one_open_work_order_per_plan",
            ),
        ]

    def __str__(self) -> str:
        return f"WO-{self.pk} {self.title} ({self.status})"

    @property
    def is_open(self) -> bool:
        return self.status in OPEN_WORK


class WorkOrderAttachment(models.Model):
    """A file on a work order (photo, report)."""

    work_order = models.ForeignKey(WorkOrder, on_delete=models.CASCADE, related_name="attachments")
    file = models.FileField(upload_to="maintenance/%Y/%m/")
    description = models.CharField(max_length=200, blank=True)
    uploaded_at = models.DateTimeField(auto_now_add=True)

    def __str__(self) -> str:
        return self.description or self.file.name


class ServiceEvent(models.Model):
    """The maintenance history of a vehicle: work orders and out of service / back."""

    class Kind(models.TextChoices):
        WORK_ORDER_DUE = "WORK_ORDER_DUE", "work order due"
        WORK_ORDER_STARTED = "WORK_ORDER_STARTED", "work order started"
        WORK_ORDER_DONE = "WORK_ORDER_DONE", "work order done"
        OUT_OF_SERVICE = "OUT_OF_SERVICE", "out of service"
        BACK_IN_SERVICE = "BACK_IN_SERVICE", "back in service"
        OVERDUE = "OVERDUE", "work order overdue"

    vehicle = models.ForeignKey(
        "robots.Vehicle", on_delete=models.CASCADE, related_name="service_events"
    )
    work_order = models.ForeignKey(
        WorkOrder, null=True, blank=True, on_delete=models.SET_NULL, related_name="events"
    )
    kind = models.CharField(max_length=20, choices=Kind.choices)
    at = models.DateTimeField()
    detail = models.CharField(max_length=300, blank=True)

    class Meta:
        ordering = ["vehicle", "-at", "-pk"]

    def __str__(self) -> str:
        return f"{self.vehicle_id} {self.kind}"


class ErrorRecord(models.Model):
    """One occurrence of a VDA 5050 error on a vehicle, from when it appeared in the state to
    when it was gone."""

    vehicle = models.ForeignKey(
        "robots.Vehicle", on_delete=models.CASCADE, related_name="error_records"
    )
    error_type = models.CharField(max_length=200)
    error_level = models.CharField(max_length=10)
    description = models.CharField(max_length=500, blank=True)
    started_at = models.DateTimeField()
    ended_at = models.DateTimeField(null=True, blank=True)

    class Meta:
        ordering = ["-started_at"]
        indexes = [models.Index(fields=["vehicle", "error_type"], name="error_record_type")]

    def __str__(self) -> str:
        return f"{self.vehicle_id} {self.error_type} ({self.error_level})"


OPEN_MOVES = ["ASSIGNED", "DRIVING"]


class ServiceMove(models.Model):
    """A drive to a park (or maintenance) station: sent by staff with the park command or when
    a vehicle is taken out of service. `control` drives it as a VDA 5050 order without
    actions, like a charge session."""

    class Status(models.TextChoices):
        ASSIGNED = "ASSIGNED", "assigned"
        DRIVING = "DRIVING", "driving"
        DONE = "DONE", "arrived"
        FAILED = "FAILED", "failed"
        CANCELLED = "CANCELLED", "cancelled"

    vehicle = models.ForeignKey(
        "robots.Vehicle", on_delete=models.CASCADE, related_name="service_moves"
    )
    station = models.ForeignKey("maps.Station", on_delete=models.CASCADE, related_name="+")
    status = models.CharField(
        max_length=10, choices=Status.choices, default=Status.ASSIGNED, db_index=True
    )
    route = models.JSONField(default=list)
    reason = models.CharField(max_length=200, blank=True)
    command_id = models.BigIntegerField(null=True, blank=True)
    note = models.CharField(max_length=200, blank=True)
    created_at = models.DateTimeField(auto_now_add=True)
    ended_at = models.DateTimeField(null=True, blank=True)

    class Meta:
        ordering = ["-created_at", "-pk"]
        constraints = [
            models.UniqueConstraint(
                fields=["vehicle"],
                condition=models.Q(status__in=OPEN_MOVES),
                name="one_open_move_per_vehicle",
            ),
            # Two vehicles are never sent to the same park station at once.
            models.UniqueConstraint(
                fields=["station"],
                condition=models.Q(status__in=OPEN_MOVES),
                name="one_open_move_per_station",
            ),
        ]

    def __str__(self) -> str:
        return f"PM-{self.pk} {self.vehicle_id} → {self.station_id} ({self.status})"

    @property
    def vda_order_id(self) -> str:
        return f"PM-{self.pk}"
