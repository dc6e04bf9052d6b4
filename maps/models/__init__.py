"""Site layouts: sites, floor maps, LIF imports and layouts, vehicle types, the graph, stations,
zones, the versions the layout editor saves, and released map files."""

from maps.models.graph import Edge, EdgeProperty, Node, NodeProperty, VehicleType
from maps.models.releases import MapRelease
from maps.models.sites import Layout, LifImport, Map, Site, floor_plan_storage
from maps.models.stations import Station, StationNode
from maps.models.versions import MapVersion
from maps.models.zones import Zone

__all__ = [
    "Edge",
    "EdgeProperty",
    "Layout",
    "LifImport",
    "Map",
    "MapRelease",
    "MapVersion",
    "Node",
    "NodeProperty",
    "Site",
    "Station",
    "StationNode",
    "VehicleType",
    "Zone",
    "floor_plan_storage",
]
