"""ADG execution: what a vehicle's progress clears, and how far its base may then reach.

Split from `traffic.manager` (the planning side): `on_progress` runs for every state message
and costs microseconds. Step i of a route (i >= 1) holds the segment from node i-1 to node i
(cleared when the vehicle reports node i) and node i (cleared when it reports node i+1, or
under grid rules when it leaves node i: `on_leave`). Base
release extends over the longest prefix whose holds have no other vehicle queued ahead (see
`traffic.reservations`), capped by the `ReleasePolicy`. A vehicle stopped by another one's hold
is noted as its waiter and re-checked when that vehicle progresses or is planned anew; with
`switching` a vehicle stopped at its decision point by a late vehicle's unreleased hold may go
ahead of it first (`traffic.switching`). Switches are not tried on a state message: one that
pushes the vehicles going behind re-times them through `propagate` (up to 150 ms on S3, 1,000
vehicles), so the stopped vehicle is left waiting and the next `tick` (which re-checks every
waiting vehicle) tries the switch: it waits at most one tick longer.
"""

from __future__ import annotations

from traffic.plans import Release, ReleasePolicy, Vehicle
from traffic.switching import Switching


class Execution(Switching):
    """Clearing and base release for a `TrafficManager` (a base class)."""

    policy: ReleasePolicy

    def on_progress(self, vehicle_id: str, passed: int, now: float) -> list[Release]:
        """The vehicle reports it reached route index `passed`: clear, then release more.

        Returns the base extensions this caused, this vehicle's first. Raises ValueError if the
        vehicle reports a node beyond its released base.
        """
        v = self.vehicle(vehicle_id)
        if passed <= v.passed:
            return []
        if passed > v.base:
            raise ValueError(f"{vehicle_id} passed index {passed} beyond its base {v.base}")
        table = self.table
        for i in range(v.passed + 1, passed + 1):
            edge = v.edge_holds[i]
            if edge is not None:
                table.remove(edge)
        for i in range(v.passed, passed):
            if i != v.left:  # (grid rules: cleared on leaving)
                table.remove(v.node_holds[i])
        v.passed = passed
        v.last_progress = now
        for goal, stop in zip(v.goals, v.stops, strict=True):
            if stop == passed:
                v.ready_at = now + goal[1]
        releases: list[Release] = []
        own = self._extend(v, now, switch=False)
        if own is not None:
            releases.append(own)
        releases.extend(self._wake(v.idx, now, switch=False))
        return releases

    def on_leave(self, vehicle_id: str, now: float) -> list[Release]:
        """Grid rules: the vehicle sets off from its last reported node along its base; the
        node's hold is cleared now (not when the next node is reached), so a vehicle queued
        for it may follow at once. Returns the base extensions this caused; nothing without
        grid rules or when the vehicle has no base to drive on."""
        v = self.vehicle(vehicle_id)
        p = v.passed
        if self.leave < 0 or p >= v.base or v.left == p:
            return []
        self.table.remove(v.node_holds[p])
        v.left = p
        return self._wake(v.idx, now, switch=False)

    def _extend(self, v: Vehicle, now: float, *, switch: bool = True) -> Release | None:
        """Extend the base over the longest releasable prefix within the policy's caps; with
        `switch` (and `switching` on) a vehicle stopped at its decision point may switch."""
        last = min(len(v.route) - 1, v.hold_at)
        b = start = v.base
        table, policy = self.table, self.policy
        was_blocked, v.blocked_by = v.blocked_by >= 0, -1
        reach = max(policy.max_distance, policy.braking_distance)
        while b < last and not v.static:
            step = b + 1
            if b > v.passed and (
                step - v.passed > policy.max_steps or v.metres[step] - v.metres[v.passed] > reach
            ):
                break
            edge, node = v.edge_holds[step], v.node_holds[step]
            blocker = (table.blocker(edge) if edge is not None else None) or table.blocker(node)
            switched = (
                blocker is not None
                and switch
                and self.switching
                and b == v.passed
                and self._switch(v, blocker, now)
            )
            if switched:
                continue  # queued ahead of the late vehicle now: check the step again
            if blocker is not None:
                v.blocked_by = blocker.vehicle
                if not was_blocked:
                    v.blocked_since = now
                self._waiters.setdefault(blocker.vehicle, set()).add(v.idx)
                break
            if edge is not None:
                table.release(edge)
            table.release(node)
            b = step
        if b == start:
            return None
        v.base = b
        return Release(v.name, v.plan_id, b, len(v.route) - 1)

    def _wake(self, idx: int, now: float, *, switch: bool = True) -> list[Release]:
        """Re-check the vehicles that waited for vehicle `idx`."""
        releases = []
        for w in self._waiters.pop(idx, ()):
            release = self._extend(self._vehicles[w], now, switch=switch)
            if release is not None:
                releases.append(release)
        return releases
