"""Inventory: load carriers, storage locations, where each load is, and how it got there."""

from django.db import models
from django.db.models import Q


class StorageLocation(models.Model):
    """A station that holds loads: how many (`capacity`) and in which numbered slots.

    Slots are 1..capacity; a load at a location may have a slot or not (the vehicle reports
    only the station, so a drop takes the lowest free slot).
    """

    station = models.OneToOneField("maps.Station", on_delete=models.CASCADE, related_name="storage")
    capacity = models.PositiveIntegerField(default=1)
    active = models.BooleanField(default=True)
    note = models.CharField(max_length=200, blank=True)

    class Meta:
        ordering = ["station__station_id"]

    def __str__(self) -> str:
        return f"{self.station.station_id} ({self.capacity})"


class LoadCarrier(models.Model):
    """A load carrier (pallet, box, rack) known by its VDA 5050 `loadId`, and where it is now.

    A load is at a storage location, on a vehicle, or nowhere known (both empty): the two
    position fields are never set together.
    """

    load_id = models.CharField(max_length=100, unique=True)
    load_type = models.CharField(max_length=100, blank=True, default="EPAL")
    length = models.FloatField(null=True, blank=True, help_text="m")
    width = models.FloatField(null=True, blank=True, help_text="m")
    height = models.FloatField(null=True, blank=True, help_text="m")
    weight = models.FloatField(null=True, blank=True, help_text="kg")
    location = models.ForeignKey(
        StorageLocation, null=True, blank=True, on_delete=models.SET_NULL, related_name="loads"
    )
    slot = models.PositiveIntegerField(null=True, blank=True)
    vehicle = models.ForeignKey(
        "robots.Vehicle",
        null=True,
        blank=True,
        on_delete=models.SET_NULL,
        related_name="load_carriers",
    )
    updated_at = models.DateTimeField(auto_now=True)

    class Meta:
        ordering = ["load_id"]
        constraints = [
            models.CheckConstraint(
                condition=Q(location__isnull=True) | Q(vehicle__isnull=True),
                name="load_in_one_place",
            ),
            models.UniqueConstraint(
                fields=["location", "slot"],
                condition=Q(slot__isnull=False),
                name="load_one_per_slot",
            ),
        ]

    def __str__(self) -> str:
        return self.load_id

    @property
    def place(self) -> str:
        if self.location is not None:
            return f"station {self.location.station.station_id}"
        if self.vehicle_id:
            return f"vehicle {self.vehicle}"
        return "unknown"


class Movement(models.Model):
    """One change of a load's place, for history and audits."""

    class Reason(models.TextChoices):
        PICK = "PICK", "picked"
        DROP = "DROP", "dropped"
        STATE = "STATE", "vehicle state"
        IMPORT = "IMPORT", "import"
        MANUAL = "MANUAL", "manual"

    load = models.ForeignKey(LoadCarrier, on_delete=models.CASCADE, related_name="movements")
    reason = models.CharField(max_length=10, choices=Reason.choices)
    from_location = models.ForeignKey(
        StorageLocation, null=True, blank=True, on_delete=models.SET_NULL, related_name="+"
    )
    from_vehicle = models.ForeignKey(
        "robots.Vehicle", null=True, blank=True, on_delete=models.SET_NULL, related_name="+"
    )
    to_location = models.ForeignKey(
        StorageLocation, null=True, blank=True, on_delete=models.SET_NULL, related_name="+"
    )
    to_vehicle = models.ForeignKey(
        "robots.Vehicle", null=True, blank=True, on_delete=models.SET_NULL, related_name="+"
    )
    order_ref = models.CharField(max_length=100, blank=True)
    at = models.DateTimeField(auto_now_add=True, db_index=True)

    class Meta:
        ordering = ["-at", "-pk"]

    def __str__(self) -> str:
        return f"{self.load} {self.reason} {self.at:%Y-%m-%d %H:%M:%S}"


class Discrepancy(models.Model):
    """A difference between what the inventory expects and what a vehicle reports.

    Open while `resolved_at` is empty; `key` is stable per cause so that detection is
    idempotent (one open discrepancy per key) and doubles as the alert's cause.
    """

    class Kind(models.TextChoices):
        UNEXPECTED_LOAD = "UNEXPECTED_LOAD", "vehicle carries a load the inventory does not expect"
        MISSING_LOAD = "MISSING_LOAD", "vehicle should carry a load but reports none"
        PICK_EMPTY = "PICK_EMPTY", "pick found nothing"
        DROP_FULL = "DROP_FULL", "drop location is full"

    key = models.CharField(max_length=200)
    kind = models.CharField(max_length=20, choices=Kind.choices)
    load_id = models.CharField(max_length=100, blank=True)
    vehicle = models.ForeignKey(
        "robots.Vehicle", null=True, blank=True, on_delete=models.SET_NULL, related_name="+"
    )
    location = models.ForeignKey(
        StorageLocation, null=True, blank=True, on_delete=models.SET_NULL, related_name="+"
    )
    order_ref = models.CharField(max_length=100, blank=True)
    message = models.TextField()
    detected_at = models.DateTimeField(auto_now_add=True)
    resolved_at = models.DateTimeField(null=True, blank=True)

    class Meta:
        ordering = ["-detected_at", "-pk"]
        verbose_name_plural = "discrepancies"
        constraints = [
            models.UniqueConstraint(
                fields=["key"], condition=Q(resolved_at__isnull=True), name="discrepancy_open_once"
            ),
        ]

    def __str__(self) -> str:
        return f"{self.kind}: {self.message[:60]}"
