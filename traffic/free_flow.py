"""The free-flow time of a task: what a vehicle alone on the layout needs for its goals.

The reference that throughput ratios are measured against (`bench.traffic`); a search against
an empty reservation table, one table per layout size. Re-exported by `traffic.des`.
"""

from __future__ import annotations

from collections.abc import Sequence

from traffic.manager import TrafficManager
from traffic.plans import Goal
from traffic.reservations import INF, ReservationTable
from traffic.sipp import ClassGraph, search


def free_flow_time(
    manager: TrafficManager, vehicle_class: int, start: int, heading: int, goals: Sequence[Goal]
) -> float:
    """Seconds a vehicle alone on the layout needs for `goals` (turns and dwells included)."""
    graph: ClassGraph = manager.graphs[vehicle_class]
    targets = [(manager.layout.node(g.node), g.dwell) for g in goals]
    path = search(graph, _EMPTY.get(manager), -1, start, heading, 0.0, INF, targets)
    if path is None:
        return INF
    return path.arrive[-1] + targets[-1][1]


class _Empty:
    """Empty reservation tables, one per layout size."""

    def __init__(self) -> None:
        self._tables: dict[int, ReservationTable] = {}

    def get(self, manager: TrafficManager) -> ReservationTable:
        count = manager.layout.resource_count
        if count not in self._tables:
            self._tables[count] = ReservationTable(count)
        return self._tables[count]


_EMPTY = _Empty()

__all__ = ["free_flow_time"]
