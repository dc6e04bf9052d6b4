"""Reads of layouts: routing graphs, plain layout data, LIF export, validation."""

from maps.selectors.graph import (
    clear_graph_cache,
    load_graph,
    load_graph_for_routing,
    load_site_graph,
    vehicle_profile,
)
from maps.selectors.layout import export_map_lif, export_site_lif, get_default_map, layout_as_dict
from maps.selectors.validation import Finding, validate_layout

__all__ = [
    "Finding",
    "clear_graph_cache",
    "export_map_lif",
    "export_site_lif",
    "get_default_map",
    "layout_as_dict",
    "load_graph",
    "load_graph_for_routing",
    "load_site_graph",
    "validate_layout",
    "vehicle_profile",
]
