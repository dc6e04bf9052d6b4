"""Traffic: planning and execution of routes, framework-free.

The first cut holds the routing graph (shortest paths on the layout); SIPP planning against a
reservation table and the action dependency graph follow (issue 6, see shared/docs/TRAFFIC.md).
"""

from traffic.routing import NoRouteError, RoutingGraph

__all__ = ["NoRouteError", "RoutingGraph"]
