"""Traffic: planning and execution of routes, framework-free.

Routing on the layout graph lives here: distances, travel times per vehicle profile with turning
and LIF vehicle-type rules, alternatives, cached distance tables, multi-floor routes, reachability.
Traffic management (issue 6, shared/docs/TRAFFIC.md): the layout as indexed arrays
(`traffic.layout`), footprint conflict sets (`traffic.footprint`), prioritized SIPP
(`traffic.sipp`) against a reservation table that doubles as the action dependency graph
(`traffic.reservations`), re-timing after delays (`traffic.timing`) and the `TrafficManager`
that control calls per order and per state message (`traffic.manager`, its queries and
`block`/`restore` in `traffic.queries`).
"""

from traffic.costs import EdgeRule, NodeRule, VehicleProfile
from traffic.elements import GraphEdge, GraphNode, NoRouteError, Route
from traffic.footprint import ConflictSets, VehicleClass
from traffic.geometry import Nurbs
from traffic.layout import Layout
from traffic.manager import NoPlanError, TrafficManager
from traffic.plans import Goal, Plan, Release, ReleasePolicy
from traffic.routing import RoutingGraph

__all__ = [
    "ConflictSets",
    "EdgeRule",
    "GraphEdge",
    "Goal",
    "GraphNode",
    "Layout",
    "NoPlanError",
    "NoRouteError",
    "NodeRule",
    "Nurbs",
    "Plan",
    "Release",
    "ReleasePolicy",
    "Route",
    "RoutingGraph",
    "TrafficManager",
    "VehicleClass",
    "VehicleProfile",
]
