"""The layout graph: nodes, directed edges, vehicle types and their per-type properties (LIF)."""

from django.db import models


class VehicleType(models.Model):
    """A kind of vehicle as LIF names it (`vehicleTypeId`, by convention "manufacturer.series").

    Types are shared by all sites and never prefixed on import: the same id means the same kind of
    vehicle. `max_speed` (m/s) and `rotation_speed` (rad/s) price routes for the type.
    """

    type_id = models.CharField(max_length=100, unique=True)
    name = models.CharField(max_length=200, blank=True)
    manufacturer = models.CharField(max_length=100, blank=True)
    series_name = models.CharField(max_length=100, blank=True)
    max_speed = models.FloatField(null=True, blank=True, help_text="m/s")
    rotation_speed = models.FloatField(null=True, blank=True, help_text="rad/s")
    height = models.FloatField(null=True, blank=True, help_text="m, highest point when loaded")

    class Meta:
        ordering = ["type_id"]

    def __str__(self) -> str:
        return self.name or self.type_id


class Node(models.Model):
    """A point of the layout in metres (right-handed, z up); `theta`: heading to hold, rad.

    A node with properties (`NodeProperty`) is usable only by those vehicle types; a node without
    any is open to every vehicle.
    """

    map = models.ForeignKey("maps.Map", on_delete=models.CASCADE, related_name="nodes")
    node_id = models.CharField(max_length=100)
    x = models.FloatField()
    y = models.FloatField()
    theta = models.FloatField(null=True, blank=True)
    name = models.CharField(max_length=200, blank=True)
    description = models.TextField(blank=True)
    layout = models.ForeignKey(
        "maps.Layout", on_delete=models.SET_NULL, related_name="nodes", null=True, blank=True
    )
    source_id = models.CharField(
        max_length=100, blank=True, help_text="nodeId in the LIF file, when it was prefixed"
    )

    class Meta:
        ordering = ["map", "node_id"]
        constraints = [
            models.UniqueConstraint(fields=["map", "node_id"], name="node_id_unique_per_map"),
        ]

    def __str__(self) -> str:
        return self.node_id


class NodeProperty(models.Model):
    """What one vehicle type does at a node (LIF vehicleTypeNodeProperty): heading and actions.

    `actions` are LIF action templates ({actionType, requirementType, blockingType, ...}).
    """

    node = models.ForeignKey(Node, on_delete=models.CASCADE, related_name="properties")
    vehicle_type = models.ForeignKey(VehicleType, on_delete=models.CASCADE, related_name="+")
    theta = models.FloatField(null=True, blank=True, help_text="rad")
    actions = models.JSONField(default=list, blank=True)

    class Meta:
        ordering = ["node", "vehicle_type"]
        verbose_name_plural = "node properties"
        constraints = [
            models.UniqueConstraint(fields=["node", "vehicle_type"], name="node_property_per_type"),
        ]

    def __str__(self) -> str:
        return f"{self.node} / {self.vehicle_type}"


class Edge(models.Model):
    """A directed connection between two nodes; two-way aisles are two edges.

    The edge belongs to its start node's map; an end node on another map makes it a transition
    between floors (a lift, a ramp). `max_speed` limits every vehicle; an edge with properties
    (`EdgeProperty`) is usable only by those vehicle types.
    """

    map = models.ForeignKey("maps.Map", on_delete=models.CASCADE, related_name="edges")
    edge_id = models.CharField(max_length=100)
    start = models.ForeignKey(Node, on_delete=models.CASCADE, related_name="outgoing")
    end = models.ForeignKey(Node, on_delete=models.CASCADE, related_name="incoming")
    length = models.FloatField(help_text="metres")
    max_speed = models.FloatField(null=True, blank=True, help_text="m/s")
    name = models.CharField(max_length=200, blank=True)
    description = models.TextField(blank=True)
    layout = models.ForeignKey(
        "maps.Layout", on_delete=models.SET_NULL, related_name="edges", null=True, blank=True
    )
    source_id = models.CharField(
        max_length=100, blank=True, help_text="edgeId in the LIF file, when it was prefixed"
    )

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


class EdgeProperty(models.Model):
    """What one vehicle type may do on an edge (LIF vehicleTypeEdgeProperty).

    Orientation: `vehicle_orientation` rad, relative to the direction of travel (TANGENTIAL, the
    default when blank) or absolute (GLOBAL). Rotation: on the edge (`rotation_allowed`) and on
    the spot at either end (NONE, CCW, CW, BOTH; blank = BOTH). Load restriction: `load_unloaded`
    / `load_loaded` (both null: none given) and the factsheet load sets allowed when loaded.
    `trajectory` is the LIF NURBS ({degree, knotVector, controlPoints}); `reentry_allowed` null
    means LIF's default (true).
    """

    class Orientation(models.TextChoices):
        GLOBAL = "GLOBAL", "global"
        TANGENTIAL = "TANGENTIAL", "tangential"

    class Rotation(models.TextChoices):
        NONE = "NONE", "none"
        CCW = "CCW", "counter-clockwise"
        CW = "CW", "clockwise"
        BOTH = "BOTH", "both"

    edge = models.ForeignKey(Edge, on_delete=models.CASCADE, related_name="properties")
    vehicle_type = models.ForeignKey(VehicleType, on_delete=models.CASCADE, related_name="+")
    vehicle_orientation = models.FloatField(null=True, blank=True, help_text="rad")
    orientation_type = models.CharField(max_length=10, choices=Orientation.choices, blank=True)
    rotation_allowed = models.BooleanField(default=False)
    rotation_at_start = models.CharField(max_length=4, choices=Rotation.choices, blank=True)
    rotation_at_end = models.CharField(max_length=4, choices=Rotation.choices, blank=True)
    max_speed = models.FloatField(null=True, blank=True, help_text="m/s")
    max_rotation_speed = models.FloatField(null=True, blank=True, help_text="rad/s")
    min_height = models.FloatField(null=True, blank=True, help_text="m, load handling device")
    max_height = models.FloatField(null=True, blank=True, help_text="m, vehicle with load")
    load_unloaded = models.BooleanField(null=True, blank=True)
    load_loaded = models.BooleanField(null=True, blank=True)
    load_set_names = models.JSONField(null=True, blank=True)
    actions = models.JSONField(default=list, blank=True)
    trajectory = models.JSONField(null=True, blank=True)
    reentry_allowed = models.BooleanField(null=True, blank=True)

    class Meta:
        ordering = ["edge", "vehicle_type"]
        verbose_name_plural = "edge properties"
        constraints = [
            models.UniqueConstraint(fields=["edge", "vehicle_type"], name="edge_property_per_type"),
        ]

    def __str__(self) -> str:
        return f"{self.edge} / {self.vehicle_type}"
