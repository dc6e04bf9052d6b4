"""Which nodes a vehicle can reach and leave again: the basis of layout validation.

The main area is the largest strongly connected set of usable nodes (from any node in it a
vehicle can drive to any other and back). Every other usable node is either unreachable from the
main area or a dead end (reachable, but with no way back to the main area).
"""

from dataclasses import dataclass

import rustworkx as rx

from traffic.costs import VehicleProfile
from traffic.routing import RoutingGraph


@dataclass(frozen=True)
class Reachability:
    """Reachability of the usable nodes of a graph for one vehicle profile."""

    usable: frozenset[str]
    main: frozenset[str]
    unreachable: frozenset[str]
    dead_ends: frozenset[str]
    component: dict[str, int]  # node id -> index of its strongly connected component

    def way_back(self, start: str, end: str) -> bool:
        """Whether a vehicle that drove from `start` to `end` can get back to `start`."""
        return self.component.get(start) == self.component.get(end)


def analyse(graph: RoutingGraph, vehicle: VehicleProfile | None = None) -> Reachability:
    """The main area, unreachable nodes and dead ends of `graph` as `vehicle` may use it."""
    profile = vehicle or VehicleProfile()
    usable = [n for n in graph.nodes.values() if n.usable_by(profile)]
    digraph: rx.PyDiGraph = rx.PyDiGraph()
    index = {n.node_id: digraph.add_node(n.node_id) for n in usable}
    digraph.add_edges_from_no_data(
        [
            (index[e.start], index[e.end])
            for e in graph.edges
            if e.start in index and e.end in index and e.rule_for(profile) is not None
        ]
    )
    components = sorted(
        rx.strongly_connected_components(digraph),
        key=lambda members: (-len(members), min(digraph[i] for i in members)),
    )
    component = {digraph[i]: c for c, members in enumerate(components) for i in members}
    if not components:
        return Reachability(frozenset(), frozenset(), frozenset(), frozenset(), {})
    main_indices = set(components[0])
    start = next(iter(main_indices))
    downstream = set(rx.descendants(digraph, start)) | {start}
    upstream = set(rx.ancestors(digraph, start)) | {start}
    names = {i: digraph[i] for i in index.values()}
    return Reachability(
        usable=frozenset(index),
        main=frozenset(names[i] for i in main_indices),
        unreachable=frozenset(names[i] for i in index.values() if i not in downstream),
        dead_ends=frozenset(
            names[i] for i in index.values() if i in downstream and i not in upstream
        ),
        component=component,
    )
