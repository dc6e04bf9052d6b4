"""Site layouts: maps with nodes, directed edges and stations."""

from django.db import models


class Map(models.Model):
    """One layout (one floor): a directed graph of nodes and edges plus stations on its nodes.

    `map_id` is the VDA 5050 `mapId` the vehicles know this layout by.
    """

    map_id = models.CharField(max_length=100, unique=True)
    name = models.CharField(max_length=200)
    description = models.TextField(blank=True)
    created_at = models.DateTimeField(auto_now_add=True)
    updated_at = models.DateTimeField(auto_now=True)

    class Meta:
        ordering = ["map_id"]

    def __str__(self) -> str:
        return self.name or self.map_id


class Node(models.Model):
    """A point of the layout in metres (right-handed, z up); `theta`: heading to hold, rad."""

    map = models.ForeignKey(Map, on_delete=models.CASCADE, related_name="nodes")
    node_id = models.CharField(max_length=100)
    x = models.FloatField()
    y = models.FloatField()
    theta = models.FloatField(null=True, blank=True)

    class Meta:
        ordering = ["map", "node_id"]
        constraints = [
            models.UniqueConstraint(fields=["map", "node_id"], name="node_id_unique_per_map"),
        ]

    def __str__(self) -> str:
        return self.node_id


class Edge(models.Model):
    """A directed connection between two nodes of one map; two-way aisles are two edges."""

    map = models.ForeignKey(Map, on_delete=models.CASCADE, related_name="edges")
    edge_id = models.CharField(max_length=100)
    start = models.ForeignKey(Node, on_delete=models.CASCADE, related_name="outgoing")
    end = models.ForeignKey(Node, on_delete=models.CASCADE, related_name="incoming")
    length = models.FloatField(help_text="metres")
    max_speed = models.FloatField(null=True, blank=True, help_text="m/s")

    class Meta:
        ordering = ["map", "edge_id"]
        constraints = [
            models.UniqueConstraint(fields=["map", "edge_id"], name="edge_id_unique_per_map"),
            models.CheckConstraint(
                condition=models.Q(length__gte=0), name="edge_length_not_negative"
            ),
        ]

    def __str__(self) -> str:
        return self.edge_id


class Station(models.Model):
    """A place where vehicles do something (pick, drop, charge, park), reached at its node."""

    class Kind(models.TextChoices):
        PICK = "PICK", "pick"
        DROP = "DROP", "drop"
        CHARGE = "CHARGE", "charge"
        PARK = "PARK", "park"

    map = models.ForeignKey(Map, on_delete=models.CASCADE, related_name="stations")
    station_id = models.CharField(max_length=100)
    name = models.CharField(max_length=200, blank=True)
    kind = models.CharField(max_length=10, choices=Kind.choices)
    node = models.ForeignKey(Node, on_delete=models.PROTECT, related_name="stations")

    class Meta:
        ordering = ["map", "station_id"]
        constraints = [
            models.UniqueConstraint(fields=["map", "station_id"], name="station_id_unique_per_map"),
        ]

    def __str__(self) -> str:
        return self.name or self.station_id
