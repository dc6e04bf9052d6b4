"""Sites, their floor maps, and where layouts came from (LIF imports and LIF layouts)."""

from pathlib import Path

from django.conf import settings
from django.core.files.storage import FileSystemStorage, Storage
from django.core.validators import FileExtensionValidator, MinValueValidator
from django.db import models


def floor_plan_storage() -> Storage:
    """Where floor-plan images live: MEDIA_ROOT/MEDIA_URL when set, else BASE_DIR/media."""
    root = getattr(settings, "MEDIA_ROOT", "") or Path(settings.BASE_DIR) / "media"
    return FileSystemStorage(location=root, base_url=getattr(settings, "MEDIA_URL", "") or None)


class Site(models.Model):
    """A facility: its floor maps, and the LIF files its vehicle integrators delivered.

    Node, edge and station ids are unique across the maps of one site (the LIF importer keeps it
    so by prefixing a file whose ids clash), so routes can cross floors by node id.
    """

    site_id = models.CharField(max_length=100, unique=True)
    name = models.CharField(max_length=200, blank=True)
    description = models.TextField(blank=True)
    created_at = models.DateTimeField(auto_now_add=True)
    updated_at = models.DateTimeField(auto_now=True)

    class Meta:
        ordering = ["site_id"]

    def __str__(self) -> str:
        return self.name or self.site_id


class LifImport(models.Model):
    """One LIF file imported into a site: its meta information, the id prefix used, the report.

    Re-importing the same project (`projectIdentification`) with `replace` deletes the maps and
    layouts of the earlier import first.
    """

    site = models.ForeignKey(Site, on_delete=models.CASCADE, related_name="lif_imports")
    project = models.CharField(max_length=200, help_text="LIF projectIdentification")
    creator = models.CharField(max_length=200, blank=True)
    exported_at = models.CharField(max_length=50, blank=True, help_text="LIF exportTimestamp")
    lif_version = models.CharField(max_length=20, blank=True)
    file_name = models.CharField(max_length=255, blank=True)
    prefix = models.CharField(
        max_length=100, blank=True, help_text="put before every id of the file to avoid clashes"
    )
    report = models.JSONField(default=dict, blank=True)
    imported_at = models.DateTimeField(auto_now_add=True)

    class Meta:
        ordering = ["site", "project"]
        verbose_name = "LIF import"
        constraints = [
            models.UniqueConstraint(fields=["site", "project"], name="lif_project_once_per_site"),
        ]

    def __str__(self) -> str:
        return f"{self.project} ({self.site})"


class Map(models.Model):
    """One floor map: the nodes, edges and stations vehicles localise on as one VDA 5050 `mapId`.

    `map_id` is the `mapId` the vehicles know this map by. `level` names the floor within the
    site (LIF `layoutLevelId`). The floor plan is a background image: `floor_plan_scale` metres
    per pixel, and its bottom-left corner at (`floor_plan_origin_x`, `floor_plan_origin_y`) m,
    turned by `floor_plan_rotation` rad. `revision` counts layout changes; routing caches key on
    it. `version` is the latest version saved in the layout editor (`MapVersion`). Maps without a
    site are standalone (the demo warehouse).
    """

    site = models.ForeignKey(
        Site, on_delete=models.CASCADE, related_name="maps", null=True, blank=True
    )
    map_id = models.CharField(max_length=100, unique=True)
    name = models.CharField(max_length=200)
    description = models.TextField(blank=True)
    level = models.CharField(max_length=100, blank=True, help_text="floor within the site")
    floor_plan = models.FileField(
        storage=floor_plan_storage,
        upload_to="floor-plans/",
        blank=True,
        validators=[FileExtensionValidator(["png", "jpg", "jpeg", "svg", "webp"])],
    )
    floor_plan_scale = models.FloatField(
        null=True, blank=True, validators=[MinValueValidator(1e-6)], help_text="metres per pixel"
    )
    floor_plan_origin_x = models.FloatField(default=0.0, help_text="m")
    floor_plan_origin_y = models.FloatField(default=0.0, help_text="m")
    floor_plan_rotation = models.FloatField(default=0.0, help_text="rad")
    lif_import = models.ForeignKey(
        LifImport, on_delete=models.SET_NULL, related_name="maps", null=True, blank=True
    )
    source_id = models.CharField(
        max_length=100, blank=True, help_text="mapId in the LIF file, when it was prefixed"
    )
    revision = models.PositiveIntegerField(default=0, editable=False)
    version = models.PositiveIntegerField(
        default=0, editable=False, help_text="latest version saved in the layout editor"
    )
    created_at = models.DateTimeField(auto_now_add=True)
    updated_at = models.DateTimeField(auto_now=True)

    class Meta:
        ordering = ["map_id"]

    def __str__(self) -> str:
        return self.name or self.map_id


class Layout(models.Model):
    """One LIF layout: how an integrator grouped nodes, edges and stations (one plane each).

    Kept so a LIF export gives back the layouts it came in; the graph itself belongs to maps.
    """

    site = models.ForeignKey(Site, on_delete=models.CASCADE, related_name="layouts")
    lif_import = models.ForeignKey(
        LifImport, on_delete=models.CASCADE, related_name="layouts", null=True, blank=True
    )
    layout_id = models.CharField(max_length=100)
    name = models.CharField(max_length=200, blank=True)
    version = models.CharField(max_length=50, blank=True)
    level_id = models.CharField(max_length=100, blank=True)
    description = models.TextField(blank=True)
    position = models.PositiveIntegerField(default=0, help_text="order in the LIF file")

    class Meta:
        ordering = ["site", "position", "layout_id"]
        verbose_name = "LIF layout"
        constraints = [
            models.UniqueConstraint(fields=["site", "layout_id"], name="layout_id_unique_per_site"),
        ]

    def __str__(self) -> str:
        return self.name or self.layout_id
