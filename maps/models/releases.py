"""Released map files: what master control distributes to VDA 5050 2.1/3.0 vehicles."""

from django.conf import settings
from django.db import models


class MapRelease(models.Model):
    """One released version of a map, as the file vehicles download (REFERENCE K.47).

    The file is the map's layout exported as LIF 1.0 JSON at release time (`content`), with its
    SHA-256 `checksum` (sent as `mapHash`). `version` is the `mapVersion` vehicles report in
    `state.maps`; it is "r<number>" so it never looks like a version a vehicle shipped with.
    `token` makes the download URL unguessable: vehicles cannot log in, so the URL is the secret.
    A release is only pushed to vehicles once distributed (`distributed_at`); the latest
    distributed release of a map is the one its vehicles must have enabled.
    """

    class Format(models.TextChoices):
        LIF = "LIF", "VDMA LIF 1.0 (JSON)"

    map = models.ForeignKey("maps.Map", on_delete=models.CASCADE, related_name="releases")
    number = models.PositiveIntegerField()
    version = models.CharField(max_length=50, help_text="mapVersion sent to vehicles")
    file_format = models.CharField(max_length=10, choices=Format.choices, default=Format.LIF)
    content = models.BinaryField(editable=False)
    checksum = models.CharField(max_length=64, help_text="SHA-256 of the file (mapHash)")
    size = models.PositiveIntegerField(default=0, help_text="bytes")
    revision = models.PositiveIntegerField(help_text="the map's revision when released")
    token = models.CharField(max_length=64, unique=True, editable=False)
    note = models.CharField(max_length=500, blank=True)
    created_at = models.DateTimeField(auto_now_add=True)
    created_by = models.ForeignKey(
        settings.AUTH_USER_MODEL, on_delete=models.SET_NULL, null=True, blank=True, related_name="+"
    )
    distributed_at = models.DateTimeField(null=True, blank=True)
    distributed_by = models.ForeignKey(
        settings.AUTH_USER_MODEL, on_delete=models.SET_NULL, null=True, blank=True, related_name="+"
    )

    class Meta:
        ordering = ["map", "-number"]
        constraints = [
            models.UniqueConstraint(fields=["map", "number"], name="map_release_number_once"),
            models.UniqueConstraint(fields=["map", "version"], name="map_release_version_once"),
        ]

    def __str__(self) -> str:
        return f"{self.map.map_id} {self.version}"

    @property
    def file_name(self) -> str:
        return f"{self.map.map_id}-{self.version}.lif.json"
