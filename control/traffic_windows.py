"""Which part of a traffic plan each VDA 5050 order message carries (mixed into TrafficLink).

A plan is the route from where the order started (or, after a re-adoption, from its decision
point, `Tracked.offset` route indices into the order); the base traffic released goes out as
released nodes, at most the message size and `horizon` unreleased nodes after it.
"""

import time
from typing import TYPE_CHECKING

from control.execution import OrderExecution, Window
from control.live import LiveVehicle
from control.traffic_support import Tracked, name, window
from traffic import Plan, TrafficManager

if TYPE_CHECKING:
    from collections.abc import Mapping


class OrderWindows:
    """Mixed into `control.traffic_link.TrafficLink` (which sets these attributes)."""

    tracked: "Mapping[str, Tracked]"
    managers: "Mapping[str, TrafficManager]"

    def start(
        self, vehicle: LiveVehicle, order_id: str, map_id: str, goals: list[str], now: float
    ) -> Plan | None:
        raise NotImplementedError  # TrafficLink.start

    def route(self, vehicle: LiveVehicle) -> tuple[list[str], int, list[int]]:
        """The vehicle's planned route (node ids), its released base end and its goal indices."""
        tracked = self.tracked[name(vehicle)]
        manager = self.managers[tracked.map_id]
        v = manager.vehicle(name(vehicle))
        ids = manager.layout.node_ids
        return [ids[n] for n in v.route], v.base, [s for s in v.stops if s < len(v.route)]

    def first_window(
        self,
        vehicle: LiveVehicle,
        execution: OrderExecution,
        map_id: str,
        max_nodes: int | None,
        horizon: int | None = None,
    ) -> Window | None:
        """Plan a new execution (its route becomes the plan) and the window of its first
        message; None when no plan exists now (the order waits for the next sync)."""
        goals = [execution.route[i] for i in execution.stop_indices]
        plan = self.start(vehicle, execution.vda_order_id, map_id, goals, time.monotonic())
        if plan is None:
            return None
        execution.route = list(plan.nodes)
        execution.move_stops(plan.stops)
        return window(len(plan.nodes), 0, plan.base_end, max_nodes, horizon)

    def next_window(
        self,
        vehicle: LiveVehicle,
        execution: OrderExecution,
        max_nodes: int | None,
        horizon: int | None = None,
    ) -> Window | None:
        """The window of an update extending the base to what traffic released, or None.

        The route beyond the sent base may have been re-planned: the execution takes the new
        one (the base, indices up to `released_until`, never changes)."""
        route, base, stops = self.route(vehicle)
        offset = self.tracked[name(vehicle)].offset
        if offset:  # re-adopted: the plan continues the order from its decision point
            route = execution.route[:offset] + route
            base, stops = base + offset, [s + offset for s in stops]
        first = execution.released_until
        if base <= first:
            return None
        execution.route = route
        # A re-plan keeps only the goals still ahead: they are the last stops of the order.
        current = execution.stop_indices
        if 0 < len(stops) <= len(current):
            execution.move_stops(current[: len(current) - len(stops)] + stops)
        extension = window(len(route), first, base, max_nodes, horizon)
        return extension if extension.released > first else None
