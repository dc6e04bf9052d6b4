"""A LIF file as read: plain data with every reference checked and the JSON path of each part.

Actions and trajectories are kept in their LIF shape (checked, camelCase), because that is how they
are stored and exported again.
"""

from dataclasses import dataclass, field
from typing import Any


@dataclass
class NodeProps:
    """A vehicleTypeNodeProperty."""

    vehicle_type: str
    theta: float | None = None
    actions: list[dict[str, Any]] = field(default_factory=list)


@dataclass
class LifNode:
    """A node; `map_id` is the VDA 5050 mapId it is on."""

    node_id: str
    x: float
    y: float
    map_id: str
    layout: str
    path: str
    name: str = ""
    description: str = ""
    props: list[NodeProps] = field(default_factory=list)
    theta: float | None = None  # openFleet extension: heading for every vehicle


@dataclass
class EdgeProps:
    """A vehicleTypeEdgeProperty (load restriction flattened)."""

    vehicle_type: str
    rotation_allowed: bool
    vehicle_orientation: float | None = None
    orientation_type: str = ""
    rotation_at_start: str = ""
    rotation_at_end: str = ""
    max_speed: float | None = None
    max_rotation_speed: float | None = None
    min_height: float | None = None
    max_height: float | None = None
    load_unloaded: bool | None = None
    load_loaded: bool | None = None
    load_set_names: list[str] | None = None
    actions: list[dict[str, Any]] = field(default_factory=list)
    trajectory: dict[str, Any] | None = None
    reentry_allowed: bool | None = None


@dataclass
class LifEdge:
    """A directed edge; its end node may be in another layout (a transition)."""

    edge_id: str
    start: str
    end: str
    layout: str
    path: str
    name: str = ""
    description: str = ""
    props: list[EdgeProps] = field(default_factory=list)
    max_speed: float | None = None  # openFleet extension: limit for every vehicle


@dataclass
class LifStation:
    """A station with its interaction nodes (first = primary)."""

    station_id: str
    node_ids: list[str]
    layout: str
    path: str
    name: str = ""
    description: str = ""
    height: float | None = None
    position: tuple[float, float, float | None] | None = None
    kind: str = ""  # openFleet extension; inferred from node actions when missing


@dataclass
class LifZone:
    """A zone from a layout's openFleet extension, in our model's field names."""

    zone_id: str
    map_id: str
    zone_type: str
    path: str
    fields: dict[str, Any] = field(default_factory=dict)  # Zone model fields besides ids
    vehicle_types: list[str] = field(default_factory=list)


@dataclass
class LifLayout:
    """A layout: one plane of nodes, edges and stations."""

    layout_id: str
    version: str
    path: str
    name: str = ""
    level_id: str = ""
    description: str = ""
    nodes: list[LifNode] = field(default_factory=list)
    edges: list[LifEdge] = field(default_factory=list)
    stations: list[LifStation] = field(default_factory=list)
    zones: list[LifZone] = field(default_factory=list)  # openFleet extension


@dataclass
class LifDocument:
    """A whole LIF file."""

    project: str
    creator: str
    export_timestamp: str
    lif_version: str
    layouts: list[LifLayout] = field(default_factory=list)

    def nodes(self) -> list[LifNode]:
        return [n for layout in self.layouts for n in layout.nodes]

    def edges(self) -> list[LifEdge]:
        return [e for layout in self.layouts for e in layout.edges]

    def stations(self) -> list[LifStation]:
        return [s for layout in self.layouts for s in layout.stations]

    def zones(self) -> list[LifZone]:
        return [z for layout in self.layouts for z in layout.zones]

    def vehicle_types(self) -> list[str]:
        """Every vehicle type id named, in order of first mention."""
        seen: dict[str, None] = {}
        for node in self.nodes():
            seen.update((p.vehicle_type, None) for p in node.props)
        for edge in self.edges():
            seen.update((p.vehicle_type, None) for p in edge.props)
        for zone in self.zones():
            seen.update((t, None) for t in zone.vehicle_types)
        return list(seen)
