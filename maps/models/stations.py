"""Stations: places where vehicles do something, reached at one or more interaction nodes."""

from django.db import models


class Station(models.Model):
    """A place where vehicles do something (pick, drop, hand over, charge, park).

    LIF lets a station have several interaction nodes (`StationNode`, in file order) and the
    fleet manager choose among them; `node` is the primary one, the first of them. `height` (m),
    the position and `description` come from LIF and are informative.
    """

    class Kind(models.TextChoices):
        PICK = "PICK", "pick"
        DROP = "DROP", "drop"
        HANDOVER = "HANDOVER", "handover (pick and drop)"
        CHARGE = "CHARGE", "charge"
        PARK = "PARK", "park"
        OTHER = "OTHER", "other"

    map = models.ForeignKey("maps.Map", on_delete=models.CASCADE, related_name="stations")
    station_id = models.CharField(max_length=100)
    name = models.CharField(max_length=200, blank=True)
    kind = models.CharField(max_length=10, choices=Kind.choices)
    node = models.ForeignKey("maps.Node", on_delete=models.PROTECT, related_name="stations")
    interaction_nodes = models.ManyToManyField(
        "maps.Node", through="maps.StationNode", related_name="interaction_stations"
    )
    description = models.TextField(blank=True)
    height = models.FloatField(null=True, blank=True, help_text="m")
    position_x = models.FloatField(null=True, blank=True, help_text="m, for display")
    position_y = models.FloatField(null=True, blank=True, help_text="m, for display")
    position_theta = models.FloatField(null=True, blank=True, help_text="rad, for display")
    layout = models.ForeignKey(
        "maps.Layout", on_delete=models.SET_NULL, related_name="stations", null=True, blank=True
    )
    source_id = models.CharField(
        max_length=100, blank=True, help_text="stationId in the LIF file, when it was prefixed"
    )

    class Meta:
        ordering = ["map", "station_id"]
        constraints = [
            models.UniqueConstraint(fields=["map", "station_id"], name="station_id_unique_per_map"),
        ]

    def __str__(self) -> str:
        return self.name or self.station_id


class StationNode(models.Model):
    """One interaction node of a station, in the order the layout lists them (0 = primary)."""

    station = models.ForeignKey(Station, on_delete=models.CASCADE, related_name="station_nodes")
    node = models.ForeignKey("maps.Node", on_delete=models.CASCADE, related_name="station_nodes")
    position = models.PositiveIntegerField(default=0)

    class Meta:
        ordering = ["station", "position"]
        constraints = [
            models.UniqueConstraint(fields=["station", "node"], name="station_node_once"),
        ]

    def __str__(self) -> str:
        return f"{self.station} @ {self.node}"
