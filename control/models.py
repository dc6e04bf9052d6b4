"""What `control` records about vehicles beyond their snapshot: map and zone-set distribution."""

from django.db import models


class VehicleMap(models.Model):
    """One map on one vehicle as `control` last saw it (REFERENCE K.47, L.48).

    Written by `control` (`control.map_store.save_map_statuses`) from the vehicle's
    `state.maps` / 3.0 `state.zoneSets` and the distribution it drives. `released_version` is
    the map's latest distributed release ("" when none); `enabled_version` what the vehicle has
    ENABLED; `status` the distribution's step and `reason` why orders are held, when they are.
    """

    class Status(models.TextChoices):
        SYNCED = "SYNCED", "released version enabled"
        NO_RELEASE = "NO_RELEASE", "no release distributed"
        DOWNLOADING = "DOWNLOADING", "downloadMap sent"
        ENABLING = "ENABLING", "enableMap sent"
        DELETING = "DELETING", "deleteMap of an old version sent"
        FAILED = "FAILED", "distribution failed"
        UNSUPPORTED = "UNSUPPORTED", "vehicle cannot download maps"

    vehicle = models.ForeignKey("robots.Vehicle", on_delete=models.CASCADE, related_name="maps")
    map_id = models.CharField(max_length=100)
    released_version = models.CharField(max_length=50, blank=True)
    enabled_version = models.CharField(max_length=50, blank=True)
    status = models.CharField(max_length=20, choices=Status.choices)
    reason = models.CharField(max_length=500, blank=True)
    reported = models.JSONField(default=list, blank=True, help_text="state.maps as reported")
    zone_set_id = models.CharField(max_length=100, blank=True, help_text="3.0: zone set sent")
    zone_set_status = models.CharField(
        max_length=20, blank=True, help_text="3.0: SENT, DISABLED or ENABLED (the vehicle's)"
    )
    updated_at = models.DateTimeField(auto_now=True)

    class Meta:
        ordering = ["vehicle", "map_id"]
        constraints = [
            models.UniqueConstraint(fields=["vehicle", "map_id"], name="vehicle_map_once"),
        ]

    def __str__(self) -> str:
        return f"{self.vehicle} {self.map_id} {self.enabled_version or '-'}"

    @property
    def outdated(self) -> bool:
        """The vehicle's enabled version is not the released one."""
        return bool(self.released_version) and self.enabled_version != self.released_version
