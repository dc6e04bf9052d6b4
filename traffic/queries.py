"""What the traffic manager answers about its fleet, and vehicles out of automatic mode.

Split from `traffic.manager` (the planning and execution path): the queries the UI and the safety
net use (who waits for whom, wait-for cycles, stalls) and `block`/`restore` for vehicles in error,
manual mode or offline. `TrafficManager` inherits them; nothing here is called per state message.
"""

from __future__ import annotations

from traffic.footprint import ConflictSets
from traffic.layout import Layout
from traffic.plans import Plan, Release, Vehicle
from traffic.reservations import INF, Hold, ReservationTable
from traffic.timing import find_cycles


class FleetQueries:
    """Read-only views of the fleet's traffic state, and blocking vehicles (a mixin)."""

    layout: Layout
    table: ReservationTable
    conflicts: ConflictSets
    _vehicles: list[Vehicle]
    _index: dict[str, int]
    _waiters: dict[int, set[int]]

    def vehicle(self, vehicle_id: str) -> Vehicle:
        """The traffic state of a vehicle (read it, do not change it)."""
        return self._vehicles[self._index[vehicle_id]]

    def replan(self, vehicle_id: str, now: float) -> Plan | None:  # pragma: no cover
        """Re-plan the unreleased rest of a route (the manager implements it)."""
        raise NotImplementedError

    # -- queries --------------------------------------------------------------------------------

    def plan_of(self, vehicle_id: str) -> Plan:
        """The vehicle's current plan."""
        return self.vehicle(vehicle_id).snapshot(self.layout, ())

    def release_of(self, vehicle_id: str) -> Release:
        """The vehicle's current base: released up to `base_end`."""
        v = self.vehicle(vehicle_id)
        return Release(v.name, v.plan_id, v.base, len(v.route) - 1)

    def waiting_for(self, vehicle_id: str) -> list[str]:
        """The vehicles whose holds keep `vehicle_id` from extending its base (for the UI)."""
        v = self.vehicle(vehicle_id)
        step = v.base + 1
        if step >= len(v.route) or v.base > v.passed:
            return []
        found: dict[int, None] = {}
        for hold in (v.edge_holds[step], v.node_holds[step]):
            if hold is not None:
                for other in self.table.blockers(hold):
                    found[other.vehicle] = None
        return [self._vehicles[i].name for i in found]

    def wait_for_graph(self) -> dict[str, list[str]]:
        """Who waits for whom, for every vehicle stopped at its decision point."""
        return {v.name: self.waiting_for(v.name) for v in self._vehicles}

    def wait_cycles(self) -> list[list[str]]:
        """Cycles in the wait-for graph (a deadlock; must never happen)."""
        return find_cycles(self.wait_for_graph())

    def stalled(self, now: float, after: float = 60.0) -> list[str]:
        """Vehicles with route left that made no progress for `after` s, and neither did the
        vehicle at the end of their wait-for chain (no progress anywhere: must never happen)."""
        found = []
        for v in self._vehicles:
            if v.static or v.passed >= len(v.route) - 1 or now - v.last_progress <= after:
                continue
            root, seen = v, {v.idx}
            while root.blocked_by >= 0 and root.blocked_by not in seen:
                root = self._vehicles[root.blocked_by]
                seen.add(root.idx)
            if now - root.last_progress > after:
                found.append(v.name)
        return found

    # -- vehicles out of automatic mode ---------------------------------------------------------

    def block(self, vehicle_id: str, now: float, *, replan: bool = True) -> list[str]:
        """Make a vehicle a static obstacle (error, manual mode, offline).

        Its unreleased steps are dropped, what it holds is held for good, and every vehicle that
        was queued behind it is re-planned around it. Returns those vehicles. With `replan`
        False they are only returned: a caller blocking many vehicles at once (a broker outage
        takes the whole fleet offline) re-plans the ones still moving once, afterwards.
        """
        v = self.vehicle(vehicle_id)
        if v.static:
            return []
        for i in range(len(v.route) - 1, v.base, -1):
            edge = v.edge_holds[i]
            if edge is not None:
                self.table.remove(edge)
            self.table.remove(v.node_holds[i])
        v.truncate(v.base)
        v.goals, v.stops = [], []
        v.static = True
        held = [h for h in [*v.edge_holds, *v.node_holds] if h is not None and h.index >= v.passed]
        affected: dict[int, None] = {}
        for hold in held:
            hold.end = INF
            self.table.ended(hold)
            for r in hold.conflicts:
                for other in self.table.blocked[r]:
                    if other.vehicle != v.idx and not other.released:
                        affected[other.vehicle] = None
        if replan:
            for w in affected:
                self.replan(self._vehicles[w].name, now)
        self._waiters.pop(v.idx, None)
        return [self._vehicles[w].name for w in affected]

    def restore(self, vehicle_id: str, node: str, now: float) -> None:
        """Put a blocked vehicle back under traffic control, standing at `node`."""
        v = self.vehicle(vehicle_id)
        n = self.layout.node(node)
        for hold in [*v.edge_holds, *v.node_holds]:
            if hold is not None and hold in self.table.blocked[hold.resource]:
                self.table.remove(hold)
        v.restart(n)
        hold = Hold(v.idx, n, 0, now, INF, self.conflicts.of(v.cls, n))
        self.table.add_released(hold)
        v.node_holds = [hold]
        v.static = False
        v.last_progress = now
        for w in {h.vehicle for h in self.table.blocked[n] if h.vehicle != v.idx}:
            self.replan(self._vehicles[w].name, now)
