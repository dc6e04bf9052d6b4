"""Reads of layouts: routing graphs, plain layout data, LIF export, validation, zones, editor."""

from maps.selectors.editor import editor_data
from maps.selectors.graph import (
    clear_graph_cache,
    edge_speed_limits,
    load_graph,
    load_graph_for_routing,
    load_site_graph,
    vehicle_profile,
)
from maps.selectors.layout import export_map_lif, export_site_lif, get_default_map, layout_as_dict
from maps.selectors.releases import current_releases, list_releases, release_by_token
from maps.selectors.validation import Finding, validate_layout
from maps.selectors.zones import list_zones, zone_as_dict, zone_rules

__all__ = [
    "Finding",
    "clear_graph_cache",
    "current_releases",
    "edge_speed_limits",
    "editor_data",
    "export_map_lif",
    "export_site_lif",
    "get_default_map",
    "layout_as_dict",
    "list_releases",
    "list_zones",
    "load_graph",
    "load_graph_for_routing",
    "load_site_graph",
    "release_by_token",
    "validate_layout",
    "vehicle_profile",
    "zone_as_dict",
    "zone_rules",
]
