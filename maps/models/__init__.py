"""Site layouts: sites, floor maps, LIF imports and layouts, vehicle types, the graph, stations,
zones, and the versions the layout editor saves."""

from maps.models.graph import Edge, EdgeProperty, Node, NodeProperty, VehicleType
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
