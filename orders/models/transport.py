"""Transport orders from ERP/WMS and their event timeline."""

from django.conf import settings
from django.db import models


class OrderSequence(models.Model):
    """Orders one vehicle must do in turn (`TransportOrder.sequence`, by `sequence_index`).

    Dispatch gives an order of a sequence only after the ones before it are closed, and only to
    the sequence's `vehicle` (the one that got its first order); while the sequence has open
    orders, that vehicle takes no other work."""

    reference = models.CharField(max_length=100, unique=True, help_text="the client's key")
    vehicle = models.ForeignKey(
        "robots.Vehicle", null=True, blank=True, on_delete=models.SET_NULL, related_name="+"
    )
    created_at = models.DateTimeField(auto_now_add=True)

    class Meta:
        ordering = ["-created_at"]

    def __str__(self) -> str:
        return self.reference


class TransportOrder(models.Model):
    """A job for one vehicle: ordered `steps` (station + pick, drop or another action).

    A pick → drop order is the two-step case; `source` and `destination` are always the first
    and last step's stations (kept for filters, the live page and old clients). `intended_vehicle`
    or `vehicle_type` restrict which vehicle dispatch may choose. Dispatch assigns a vehicle and
    a route (node ids from the vehicle's node through every step's node; `route_steps` holds each
    step's index in it); `control` sends it as one VDA 5050 order (`vda_order_id`) and tracks it
    to the end from the vehicle's state. `earliest_start` holds an order back from dispatch until
    then; `deadline` makes it more urgent among orders of the same priority. `dispatch_note`
    says why dispatch has not assigned it yet.
    """

    class Status(models.TextChoices):
        NEW = "NEW", "new"
        ASSIGNED = "ASSIGNED", "assigned"
        IN_PROGRESS = "IN_PROGRESS", "in progress"
        FINISHED = "FINISHED", "finished"
        FAILED = "FAILED", "failed"
        CANCELLED = "CANCELLED", "cancelled"

    ACTIVE_STATUSES = (Status.ASSIGNED, Status.IN_PROGRESS)
    OPEN_STATUSES = (Status.NEW, Status.ASSIGNED, Status.IN_PROGRESS)

    source = models.ForeignKey("maps.Station", on_delete=models.PROTECT, related_name="+")
    destination = models.ForeignKey("maps.Station", on_delete=models.PROTECT, related_name="+")
    load_id = models.CharField(max_length=100, blank=True)
    load_type = models.CharField(max_length=100, blank=True, default="EPAL")
    priority = models.IntegerField(default=0, help_text="higher goes first")
    external_ref = models.CharField(max_length=200, blank=True, db_index=True)
    earliest_start = models.DateTimeField(
        null=True, blank=True, help_text="not dispatched before this time"
    )
    deadline = models.DateTimeField(null=True, blank=True, help_text="should be finished by then")
    status = models.CharField(
        max_length=20, choices=Status.choices, default=Status.NEW, db_index=True
    )
    vehicle = models.ForeignKey(
        "robots.Vehicle",
        null=True,
        blank=True,
        on_delete=models.PROTECT,
        related_name="transport_orders",
    )
    intended_vehicle = models.ForeignKey(
        "robots.Vehicle",
        null=True,
        blank=True,
        on_delete=models.SET_NULL,
        related_name="+",
        help_text="only this vehicle may do the order",
    )
    vehicle_type = models.ForeignKey(
        "maps.VehicleType",
        null=True,
        blank=True,
        on_delete=models.PROTECT,
        related_name="+",
        help_text="only vehicles of this type may do the order",
    )
    metadata = models.JSONField(default=dict, blank=True, help_text="free data of the client")
    sequence = models.ForeignKey(
        OrderSequence, null=True, blank=True, on_delete=models.PROTECT, related_name="orders"
    )
    sequence_index = models.PositiveIntegerField(null=True, blank=True)
    route = models.JSONField(default=list, blank=True, help_text="node ids to drive")
    route_steps = models.JSONField(
        default=list, blank=True, help_text="index in `route` of each step's node"
    )
    vda_order_id = models.CharField(max_length=100, blank=True)
    failure_reason = models.TextField(blank=True)
    dispatch_note = models.CharField(
        max_length=200, blank=True, help_text="why dispatch has not assigned the order yet"
    )
    cancel_requested = models.BooleanField(default=False)
    vehicle_lost_at = models.DateTimeField(
        null=True, blank=True, help_text="since when its vehicle is gone (lost-vehicle policy)"
    )
    created_by = models.ForeignKey(
        settings.AUTH_USER_MODEL, null=True, blank=True, on_delete=models.SET_NULL, related_name="+"
    )
    created_at = models.DateTimeField(auto_now_add=True)
    assigned_at = models.DateTimeField(null=True, blank=True)
    sent_at = models.DateTimeField(
        null=True, blank=True, help_text="when control published the VDA 5050 order"
    )
    started_at = models.DateTimeField(null=True, blank=True)
    finished_at = models.DateTimeField(null=True, blank=True)
    updated_at = models.DateTimeField(auto_now=True)

    class Meta:
        ordering = ["-created_at"]
        constraints = [
            # A vehicle drives one transport order at a time; the database enforces it so that
            # two concurrent dispatch runs can never double-book a vehicle.
            models.UniqueConstraint(
                fields=["vehicle"],
                condition=models.Q(status__in=["ASSIGNED", "IN_PROGRESS"]),
                name="one_active_order_per_vehicle",
            ),
            models.UniqueConstraint(
                fields=["sequence", "sequence_index"], name="one_order_per_sequence_place"
            ),
            models.CheckConstraint(
                condition=models.Q(earliest_start__isnull=True)
                | models.Q(deadline__isnull=True)
                | models.Q(deadline__gt=models.F("earliest_start")),
                name="deadline_after_earliest_start",
            ),
        ]

    def __str__(self) -> str:
        return f"TO-{self.pk} {self.source_id}→{self.destination_id} ({self.status})"

    @property
    def is_open(self) -> bool:
        return self.status in self.OPEN_STATUSES


class OrderStep(models.Model):
    """One stop of a transport order: at `station`, do `operation` (pick, drop or the custom
    VDA 5050 action `action_type`) with `parameters` as the action's parameters.

    `finished_at` comes from the vehicle's state (via `control`): the step is reached and done.
    """

    class Operation(models.TextChoices):
        PICK = "PICK", "pick"
        DROP = "DROP", "drop"
        ACTION = "ACTION", "custom action"

    order = models.ForeignKey(TransportOrder, on_delete=models.CASCADE, related_name="steps")
    index = models.PositiveSmallIntegerField(help_text="0-based position in the order")
    station = models.ForeignKey("maps.Station", on_delete=models.PROTECT, related_name="+")
    operation = models.CharField(max_length=10, choices=Operation.choices)
    action_type = models.CharField(
        max_length=100, blank=True, help_text="VDA 5050 action type of a custom action"
    )
    parameters = models.JSONField(default=dict, blank=True)
    finished_at = models.DateTimeField(
        null=True, blank=True, help_text="when the vehicle finished the step's action"
    )

    class Meta:
        ordering = ["order", "index"]
        constraints = [
            models.UniqueConstraint(fields=["order", "index"], name="order_step_index_unique")
        ]

    def __str__(self) -> str:
        return f"{self.order_id}#{self.index} {self.vda_action_type}@{self.station_id}"

    @property
    def vda_action_type(self) -> str:
        """The VDA 5050 action type the vehicle does at the station."""
        if self.operation == self.Operation.ACTION:
            return self.action_type
        return self.operation.lower()


class OrderEvent(models.Model):
    """One entry of a transport order's timeline: what happened, when, and who or why."""

    class Kind(models.TextChoices):
        CREATED = "CREATED", "created"
        ASSIGNED = "ASSIGNED", "assigned"
        STARTED = "STARTED", "started"
        STEP_REACHED = "STEP_REACHED", "step reached"
        FINISHED = "FINISHED", "finished"
        FAILED = "FAILED", "failed"
        REQUEUED = "REQUEUED", "requeued"
        UPDATED = "UPDATED", "updated"
        CANCEL_REQUESTED = "CANCEL_REQUESTED", "cancel requested"
        CANCELLED = "CANCELLED", "cancelled"

    order = models.ForeignKey(TransportOrder, on_delete=models.CASCADE, related_name="events")
    kind = models.CharField(max_length=20, choices=Kind.choices)
    at = models.DateTimeField(auto_now_add=True)
    detail = models.JSONField(default=dict, blank=True)

    class Meta:
        ordering = ["order", "at", "pk"]

    def __str__(self) -> str:
        return f"{self.order_id} {self.kind}"
