"""What traffic shows outside control's hot path (mixed into TrafficLink): whom a vehicle waits
for and what it reserved (the live page), and the safety net's counters (/metrics), with a log
line for each vehicle that newly stalls."""

import logging
from typing import TYPE_CHECKING

from control.live import LiveVehicle
from control.traffic_support import Tracked, name
from traffic import TrafficManager

if TYPE_CHECKING:
    from collections.abc import Mapping

logger = logging.getLogger("control.traffic_link")


class TrafficViews:
    """Mixed into `control.traffic_link.TrafficLink` (which sets these attributes)."""

    tracked: "Mapping[str, Tracked]"
    managers: "Mapping[str, TrafficManager]"
    _stalled_logged: set[str]

    def route(self, vehicle: LiveVehicle) -> tuple[list[str], int, list[int]]:
        raise NotImplementedError  # OrderWindows.route

    def waiting_for(self, vehicle: LiveVehicle) -> list[str]:
        """Serial numbers of the vehicles this one waits for at its decision point."""
        tracked = self.tracked.get(name(vehicle))
        if tracked is None:
            return []
        others = self.managers[tracked.map_id].waiting_for(name(vehicle))
        return [self.tracked[o].vehicle.serial_number for o in others if o in self.tracked]

    def reserved(self, vehicle: LiveVehicle) -> list[str]:
        """The node ids the vehicle has planned but not yet released (its reservations)."""
        tracked = self.tracked.get(name(vehicle))
        if tracked is None or tracked.order_id is None:
            return []
        route, base, _ = self.route(vehicle)
        return route[base + 1 :]

    def safety(self, now: float) -> dict[str, int]:
        """The safety net's counters: wait-for cycles and stalled vehicles (both must stay 0).
        A vehicle newly stalled is logged once, with what traffic and the driver know of it."""
        cycles = sum(len(m.wait_cycles()) for m in self.managers.values())
        stalled = [(m, n) for m in self.managers.values() for n in m.stalled(now)]
        for manager, vehicle_id in stalled:
            if vehicle_id not in self._stalled_logged:
                self._log_stall(manager, vehicle_id, now)
        self._stalled_logged = {n for _, n in stalled}
        return {"cycles": cycles, "stalled": len(stalled)}

    def _log_stall(self, manager: TrafficManager, vehicle_id: str, now: float) -> None:
        v = manager.vehicle(vehicle_id)
        tracked = self.tracked.get(vehicle_id)
        execution = tracked.vehicle.execution if tracked is not None else None
        blocker = manager.vehicle_ids[v.blocked_by] if v.blocked_by >= 0 else None
        logger.warning(
            "traffic: %s stalled: passed %d, base %d of %d nodes, waits for %s, no progress "
            "for %.0f s, ready in %.0f s; order %s released until %s, awaiting confirmation %s;"
            " %s",
            vehicle_id, v.passed, v.base, len(v.route), blocker, now - v.last_progress,
            v.ready_at - now, tracked.order_id if tracked else None,
            execution.released_until if execution else None,
            execution.awaiting_confirmation if execution else None,
            tracked.history(now) if tracked else "",
        )  # fmt: skip
