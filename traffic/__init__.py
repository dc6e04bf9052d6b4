"""Traffic: planning and execution of routes, framework-free.

Routing on the layout graph lives here: distances, travel times per vehicle profile with turning
and LIF vehicle-type rules, alternatives, cached distance tables, multi-floor routes, reachability.
SIPP planning against a reservation table and the action dependency graph follow (issue 6, see
shared/docs/TRAFFIC.md).
"""

from traffic.costs import EdgeRule, NodeRule, VehicleProfile
from traffic.elements import GraphEdge, GraphNode, NoRouteError, Route
from traffic.geometry import Nurbs
from traffic.routing import RoutingGraph

__all__ = [
    "EdgeRule",
    "GraphEdge",
    "GraphNode",
    "NoRouteError",
    "NodeRule",
    "Nurbs",
    "Route",
    "RoutingGraph",
    "VehicleProfile",
]
