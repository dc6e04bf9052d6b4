"""The reservation table, which is also the action dependency graph (ADG).

A **hold** is one vehicle's claim on one resource for one step of its plan, with a planned
interval `[start, end]` (plan time, seconds). Every resource r keeps one list, `blocked[r]`, of
the uncleared holds on r *and on every resource conflicting with r*, sorted by start. That one
list serves both sides of the design:

- **SIPP** reads the safe intervals of r for a vehicle: the gaps between the other vehicles' holds;
- **ADG**: the holds in `blocked[r]` are the queue of r's conflict set in planned order. A hold may
  be entered (released) only when no other vehicle's hold is ahead of it in its list.

Planned intervals of conflicting holds of different vehicles never overlap (SIPP plans into
gaps), so the order is a total order per conflict set, and because every dependency points
forward in plan time, the dependency graph is acyclic: execution cannot deadlock, whatever the
delays. A released hold moves to the front of its lists (its start becomes -inf) so that no later
plan can be queued ahead of it; a cleared hold leaves the lists.
"""

from __future__ import annotations

import bisect
import math
import operator
from collections.abc import Callable, Sequence
from typing import TYPE_CHECKING

from traffic import speedups

INF = math.inf


class PyHold:
    """One vehicle's claim on one resource during one step of its plan.

    `Hold` is this class, or its twin compiled as a C struct (`traffic._speedups.Hold`).
    """

    __slots__ = ("vehicle", "resource", "index", "start", "end", "key", "released", "conflicts")

    def __init__(
        self,
        vehicle: int,
        resource: int,
        index: int,
        start: float,
        end: float,
        conflicts: Sequence[int],
    ) -> None:
        self.vehicle = vehicle
        self.resource = resource
        self.index = index  # route index of the step
        self.start = start  # planned entry (s)
        self.end = end  # planned clearing (s); inf for a vehicle parked until further notice
        self.key = start  # sort key: start, or -inf once released
        self.released = False
        self.conflicts = conflicts  # the lists this hold is in

    def __repr__(self) -> str:
        state = "released" if self.released else "planned"
        return (
            f"Hold(v{self.vehicle} r{self.resource} #{self.index} "
            f"{self.start:.2f}-{self.end:.2f} {state})"
        )


if TYPE_CHECKING:
    Hold = PyHold
else:
    Hold = speedups.COMPILED.Hold if speedups.COMPILED else PyHold


# A hold's sort key, read in C: bisect and sort call it for every comparison, and a Python
# function there was most of `add` in control's profile (planning commits under its lock).
_key: Callable[[Hold], float] = operator.attrgetter("key")


class ReservationTable:
    """Per resource, the uncleared holds on its conflict set in planned order."""

    def __init__(self, resource_count: int) -> None:
        self.blocked: list[list[Hold]] = [[] for _ in range(resource_count)]
        self.unsorted: set[int] = set()  # lists whose keys moved (re-timing); sorted on use
        # per list: the gaps between all holds and the vehicles holding in it (SIPP asks for the
        # same lists again and again; a vehicle without holds there gets the shared gaps)
        self._gaps: dict[int, tuple[list[tuple[float, float]], set[int]]] = {}
        self._stale: set[int] = set()  # lists whose cached gaps an end change made stale
        # Changes to the lists, counted (`clock`), and per list the count at its last change:
        # a search that ran with the table open to other threads checks only the lists that
        # changed since it started (`changed_since`, `admits`).
        self.clock = 0
        self._touched = [0] * resource_count

    def sort(self, resource: int) -> None:
        """Restore key order in one list. Re-timing keeps conflicting holds in order, so this
        only reorders holds that do not conflict with each other (stable sort)."""
        if resource in self.unsorted:
            self.unsorted.discard(resource)
            self.blocked[resource].sort(key=_key)
            self._gaps.pop(resource, None)
            self._touch((resource,))

    def retimed(self, hold: Hold) -> None:
        """`hold.start` moved later: its lists need sorting before the next SIPP or insert."""
        if not hold.released:
            hold.key = hold.start
            self.unsorted.update(hold.conflicts)

    def add(self, hold: Hold) -> None:
        """Queue a planned (unreleased) hold by its start."""
        for r in hold.conflicts:
            if r in self.unsorted:
                self.sort(r)
            bisect.insort_right(self.blocked[r], hold, key=_key)
            self._gaps.pop(r, None)
        self._touch(hold.conflicts)

    def add_released(self, hold: Hold) -> None:
        """Put a hold the vehicle already occupies (a parked vehicle) at the front."""
        hold.released, hold.key = True, -INF
        for r in hold.conflicts:
            self.blocked[r].insert(0, hold)
            self._gaps.pop(r, None)
        self._touch(hold.conflicts)

    def release(self, hold: Hold) -> None:
        """Mark `hold` entered: nothing may be queued ahead of it any more."""
        if hold.released:
            return
        key = hold.key
        hold.released, hold.key = True, -INF
        for r in hold.conflicts:
            queue = self.blocked[r]
            self._drop(queue, r, hold, key)
            queue.insert(0, hold)
            self._gaps.pop(r, None)
        self._touch(hold.conflicts)

    def remove(self, hold: Hold) -> None:
        """Drop a hold: cleared by its vehicle, or an unreleased step replanned away."""
        for r in hold.conflicts:
            self._drop(self.blocked[r], r, hold, hold.key)
            self._gaps.pop(r, None)
        self._touch(hold.conflicts)

    def _drop(self, queue: list[Hold], resource: int, hold: Hold, key: float) -> None:
        """Take `hold` (sorted under `key`) out of `queue`, the list of `resource`."""
        if resource not in self.unsorted:  # sorted: look among the holds with its key only
            i = bisect.bisect_left(queue, key, key=_key)
            while i < len(queue) and queue[i] is not hold and queue[i].key == key:
                i += 1
            if i < len(queue) and queue[i] is hold:
                del queue[i]
                return
        queue.remove(hold)

    def _touch(self, resources: Sequence[int]) -> None:
        self.clock += 1
        for r in resources:
            self._touched[r] = self.clock

    def changed_since(self, resource: int, clock: int) -> bool:
        """Whether `resource`'s list may have changed since the table's `clock` read `clock`
        (re-timing marks a list unsorted or stale without counting: those count as changed)."""
        return (
            self._touched[resource] > clock or resource in self.unsorted or resource in self._stale
        )

    def admits(self, resource: int, vehicle: int, start: float, end: float) -> bool:
        """Whether `vehicle` may hold `resource` during [start, end]: no other vehicle's hold
        in its list overlaps it (a released one counts from -inf), i.e. it lies inside one of
        `safe_intervals(resource, vehicle)`."""
        if start == end:  # an instant: also refused on the seam of two holds (merged there)
            return any(a <= start <= b for a, b in self.safe_intervals(resource, vehicle))
        for hold in self.blocked[resource]:
            if hold.vehicle != vehicle and hold.key < end and hold.end > start:
                return False
        return True

    def ended(self, hold: Hold) -> None:
        """`hold.end` was changed in place: its lists' safe intervals are stale."""
        self._stale.update(hold.conflicts)

    def blocker(self, hold: Hold) -> Hold | None:
        """The first other vehicle's hold queued ahead of `hold`, or None if it may be entered."""
        me = hold.vehicle
        for other in self.blocked[hold.resource]:
            if other is hold:
                return None
            if other.vehicle != me:
                return other
        raise ValueError(f"{hold!r} is not queued")

    def blockers(self, hold: Hold) -> list[Hold]:
        """Every other vehicle's hold queued ahead of `hold`."""
        found: list[Hold] = []
        for other in self.blocked[hold.resource]:
            if other is hold:
                return found
            if other.vehicle != hold.vehicle:
                found.append(other)
        raise ValueError(f"{hold!r} is not queued")

    def safe_intervals(self, resource: int, vehicle: int) -> list[tuple[float, float]]:
        """The gaps between other vehicles' holds on `resource`'s conflict set, as (from, to).

        Released holds count from -inf: a plan may only be queued behind them. The list
        returned may be shared: do not change it.
        """
        if resource in self.unsorted:
            self.sort(resource)
        if resource in self._stale:
            self._stale.discard(resource)
            self._gaps.pop(resource, None)
            self._touch((resource,))
        cached = self._gaps.get(resource)
        if cached is None:
            cached = self._gaps[resource] = (
                self._between(resource, -1),
                {h.vehicle for h in self.blocked[resource]},
            )
        if vehicle not in cached[1]:
            return cached[0]
        return self._between(resource, vehicle)

    def _between(self, resource: int, vehicle: int) -> list[tuple[float, float]]:
        gaps: list[tuple[float, float]] = []
        free_from = -INF
        for hold in self.blocked[resource]:
            if hold.vehicle == vehicle:
                continue
            if hold.key > free_from:
                gaps.append((free_from, hold.key))
            if hold.end > free_from:
                free_from = hold.end
        if free_from < INF:
            gaps.append((free_from, INF))
        return gaps

    def first_other_start(self, resource: int, vehicle: int) -> float:
        """The earliest queue key of another vehicle's hold on `resource`'s conflict set."""
        for hold in self.blocked[resource]:
            if hold.vehicle != vehicle:
                return hold.key
        return INF
