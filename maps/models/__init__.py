"""Site layouts: sites, floor maps, LIF imports and layouts, vehicle types, the graph, stations."""

from maps.models.graph import Edge, EdgeProperty, Node, NodeProperty, VehicleType
from maps.models.sites import Layout, LifImport, Map, Site, floor_plan_storage
from maps.models.stations import Station, StationNode

__all__ = [
    "Edge",
    "EdgeProperty",
    "Layout",
    "LifImport",
    "Map",
    "Node",
    "NodeProperty",
    "Site",
    "Station",
    "StationNode",
    "VehicleType",
    "floor_plan_storage",
]
