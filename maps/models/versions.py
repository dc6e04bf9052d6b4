"""Saved versions of a map's layout (the layout editor saves each one as a new version)."""

from django.conf import settings
from django.db import models


class MapVersion(models.Model):
    """One saved version of a map's layout: who saved it, when, and the layout as saved.

    `number` counts the versions of one map from 1 (`Map.version` is the latest). `layout` is the
    editor's payload as written (nodes, edges, stations, zones), kept to see what changed and to
    go back to it; `counts` sums it up for lists.
    """

    map = models.ForeignKey("maps.Map", on_delete=models.CASCADE, related_name="versions")
    number = models.PositiveIntegerField()
    revision = models.PositiveIntegerField(help_text="the map's revision after this save")
    saved_by = models.ForeignKey(
        settings.AUTH_USER_MODEL, on_delete=models.SET_NULL, null=True, blank=True, related_name="+"
    )
    saved_at = models.DateTimeField(auto_now_add=True)
    note = models.CharField(max_length=500, blank=True)
    counts = models.JSONField(default=dict, blank=True)
    layout = models.JSONField(default=dict, blank=True)

    class Meta:
        ordering = ["map", "-number"]
        constraints = [
            models.UniqueConstraint(fields=["map", "number"], name="map_version_number_once"),
        ]

    def __str__(self) -> str:
        return f"{self.map} v{self.number}"
