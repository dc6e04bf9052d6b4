"""Switching the order of vehicles on a shared stretch (opt-in): a switchable ADG.

The plain ADG keeps every resource's queue in the order the plans were made. When the vehicle
first in a queue is late (standing in a delay, waiting itself, or still far away), a vehicle
queued behind it that stands ready at its decision point waits although the resource is free.
With `TrafficManager(switching=True)` such a waiting vehicle W may go ahead of the late one L
over a short **stretch** of its route (in the spirit of Berndt et al.'s switchable action
dependency graph): W's unreleased steps b+1..k (b its decision point; k the first node L is not
queued to pass before W) are re-timed to the earliest W can drive them and queued ahead of L's
holds there, and L is re-timed after them. So is any other vehicle whose unreleased holds W's
new times overlap; a vehicle coming the same way follows W, one coming the other way waits
before the stretch.

Why this keeps the release guarantee. Collision-freedom does not depend on the order: a hold
is entered only when no other vehicle's hold is queued ahead of it in its list, and a released
hold stays at the front. Deadlock-freedom rests on one invariant: the stored plan times are a
consistent schedule for the queues, i.e. in every list two conflicting holds of different
vehicles do not overlap in plan time and are queued in time order, and each vehicle's own steps
follow each other in time. Then every wait points forward in plan time and the wait-for graph
is acyclic whatever the delays (`traffic.reservations`). A switch keeps that invariant in two
steps, each of which keeps it on its own:

1. **The vehicles that go behind are re-timed later**: pushes "V departs from index i no
   earlier than t" (t: the end of W's new hold that V's hold must follow) through
   `propagate`, the re-timing every tick does. Pushes change no order, so the schedule stays
   consistent, and they terminate.
2. **W's stretch is re-timed earlier** to times that, with every other hold as it now is,
   overlap no other vehicle's hold (`ReservationTable.admits`, asked for each hold of the
   stretch), and that W's unchanged rest still follows (it arrives at k before it planned to
   leave k). The stretch's holds are then queued again by their new start, so each list is in
   time order again.

Only unreleased holds change places (a base is never revoked); a released hold in the way
rules a switch out. Two pre-checks keep step 2 from failing after step 1 (a wasted push):
a vehicle that goes behind must not wait on a node the stretch needs, and W must not stand
at k waiting for one of them (each would wait for the other); if step 2's check still fails
(a side effect of the pushes on a third vehicle), the switch is dropped and the pushes stay,
like any re-timing. A switch is made only when W's first step can then be released at once,
so each switch moves a vehicle (no two vehicles switch back and forth without progress), and
a vehicle tries at most once per `SWITCH_EVERY` seconds. Switches are tried in `tick()` and
when a plan is committed, never on a state message (`traffic.execution`).
"""

from __future__ import annotations

from collections.abc import Iterator

from traffic.plans import Vehicle, node_hold_end
from traffic.queries import FleetQueries
from traffic.reservations import INF, Hold
from traffic.sipp import ClassGraph
from traffic.timing import propagate, stay

# a stretch's new departures from b..k-1 and arrivals at b+1..k (b: the decision point)
Schedule = tuple[list[float], list[float]]

SWITCH_EVERY = 1.0  # s between two switch tries of one waiting vehicle
OVERDUE_GRACE = 1.0  # s past its move's duration after which a driving vehicle counts as late


class Switching(FleetQueries):
    """Letting a waiting vehicle go ahead of a late one (a `TrafficManager` base class)."""

    graphs: list[ClassGraph]
    switching: bool
    leave: float  # grid rules (>= 0): s a node stays held after its vehicle leaves it
    # s: the most a switch may push back the plan of a vehicle that goes behind (0: only
    # switches that fit before the others' plans as they are)
    switch_push: float
    switch_steps: int  # the longest stretch a switch moves (steps)
    switches: int  # switches made
    switch_pushes: int  # switches that pushed vehicles going behind (dropped ones included)
    switches_dropped: int  # switches whose final check failed after their pushes

    def _switch(self, w: Vehicle, blocker: Hold, now: float) -> bool:
        """Let `w`, standing at its decision point and stopped by `blocker` on its next step,
        go ahead of `blocker`'s vehicle over a stretch of its route; True if it did."""
        if blocker.released or now - w.switch_tried_at < SWITCH_EVERY:
            return False
        w.switch_tried_at = now
        late = self._vehicles[blocker.vehicle]
        if late.static or w.passed != w.base:
            return False
        k = self._stretch(w, late)
        if k < 0:
            return False
        times = _earliest(w, self.graphs[w.cls], k, now)
        if times is None:
            return False
        pushes = self._pushes(w, late, k, times, now)
        if pushes is None:
            return False
        if pushes:
            propagate(self._vehicles, self.table, self.graphs, pushes, self.leave)
            self.switch_pushes += 1
        if not self._fits_ahead(w, k, times):
            self.switches_dropped += bool(pushes)
            return False
        self._retime_stretch(w, k, times)
        waiters = self._waiters.setdefault(w.idx, set())
        waiters.update(idx for _, idx, _ in pushes)
        waiters.add(late.idx)
        self.switches += 1
        return True

    def _stretch(self, w: Vehicle, late: Vehicle) -> int:
        """The last route index k of the stretch: the first node from w's decision point on
        that `late` is not queued to pass before w; -1 if none within `switch_steps`."""
        b, last, blocked = w.base, len(w.route) - 1, self.table.blocked
        for k in range(b + 1, min(last, b + self.switch_steps) + 1):
            mine = w.node_holds[k]
            ahead = False
            for hold in blocked[mine.resource]:
                if hold is mine:
                    break
                if hold.vehicle == late.idx:
                    if hold.released:
                        return -1  # it is there already
                    ahead = True
                    break
            if not ahead:
                return k
        return -1

    def _stuck(self, late: Vehicle, now: float) -> bool:
        """Whether `late` is held up: stopped at its decision point (waiting or handling),
        or overdue on the move it drives (a delay)."""
        p = late.passed
        if late.base == p:
            return True
        graph = self.graphs[late.cls]
        move = graph.travel[(late.route[p], late.route[p + 1])]
        move += graph.turn(late.headings[p], late.headings[p + 1])
        return now - late.last_progress > move + OVERDUE_GRACE

    def _pushes(
        self, w: Vehicle, late: Vehicle, k: int, times: Schedule, now: float
    ) -> list[tuple[float, int, int]] | None:
        """The re-timing pushes (time, vehicle, index) that put every hold w's stretch must
        pass behind w's new hold: [] if the stretch fits as planned; None if no switch.

        The vehicles that go behind are `late` and every vehicle with an unreleased hold that
        w's new times overlap; each of their unreleased holds queued on the stretch before w's
        new hold there ends must start after it (from the first of them on). A released hold
        in the way rules the switch out, and so does a vehicle that would lose more than
        `switch_push` s, or more than w gains while it is not held up itself (a plan that
        is on time must not pay more than the switch buys). A vehicle that goes behind must
        not be kept waiting on a node the stretch needs (it would wait for w while w waits
        for it): its waiting node's hold must not overlap the stretch.
        """
        table, me = self.table, w.idx
        spans = list(_spans(w, k, times, self.leave))
        behind = {late.idx}
        for hold, start, end in spans:
            for other in table.blocked[hold.resource]:
                if other.vehicle != me and other.key < end and other.end > start:
                    if other.released:
                        return None
                    behind.add(other.vehicle)
        first: dict[int, int] = {}
        for hold, _, end in spans:
            for other in table.blocked[hold.resource]:
                if other.vehicle in behind and not other.released and other.key < end:
                    first[other.vehicle] = min(first.get(other.vehicle, other.index), other.index)
        pushes: dict[tuple[int, int], float] = {}
        for hold, _, end in spans:
            for other in table.blocked[hold.resource]:
                v = other.vehicle
                if v in first and other.index >= first[v] and other.key < end:
                    step = (v, other.index - 1)
                    pushes[step] = max(pushes.get(step, -INF), end)
        if not self._affordable(pushes, w.depart[w.base] - times[0][0], now):
            return None
        if self._waits_after_stretch(w, k, first):
            return None
        for v, j in first.items():
            if self._waits_on_stretch(self._vehicles[v], j, pushes, spans):
                return None
        return [(at, v, i) for (v, i), at in pushes.items() if at > self._vehicles[v].depart[i]]

    def _affordable(self, pushes: dict[tuple[int, int], float], gain: float, now: float) -> bool:
        """Whether no vehicle would lose more than `switch_push` s, nor (on time, not held up)
        more than w gains (`gain` s)."""
        lost: dict[int, float] = {}
        for (v, i), at in pushes.items():
            lost[v] = max(lost.get(v, 0.0), at - self._vehicles[v].depart[i])
        return all(
            delay <= self.switch_push and (delay < gain or self._stuck(self._vehicles[v], now))
            for v, delay in lost.items()
        )

    def _waits_after_stretch(self, w: Vehicle, k: int, first: dict[int, int]) -> bool:
        """Whether w's step after the stretch is queued behind a hold that goes behind w
        (w would stand at k waiting for a vehicle that waits for w to leave k)."""
        if k >= len(w.route) - 1:
            return False
        for mine in (w.edge_holds[k + 1], w.node_holds[k + 1]):
            assert mine is not None
            for other in self.table.blocked[mine.resource]:
                if other is mine:
                    break
                if other.vehicle in first and other.index >= first[other.vehicle]:
                    return True
        return False

    def _waits_on_stretch(
        self,
        v: Vehicle,
        j: int,
        pushes: dict[tuple[int, int], float],
        spans: list[tuple[Hold, float, float]],
    ) -> bool:
        """Whether `v`, pushed to leave its index j-1 later, would then stand there during
        one of w's new holds on a conflicting resource."""
        waiting = v.node_holds[j - 1]
        leaves = pushes.get((v.idx, j - 1), v.depart[j - 1])
        arrives = leaves + self.graphs[v.cls].travel[(v.route[j - 1], v.route[j])]
        end = max(waiting.end, node_hold_end(leaves, arrives, self.leave))
        return any(
            hold.resource in waiting.conflicts and waiting.key < e and end > s
            for hold, s, e in spans
        )

    def _fits_ahead(self, w: Vehicle, k: int, times: Schedule) -> bool:
        """Whether w's stretch at `times` overlaps no other vehicle's hold, and its first step
        then has nobody queued ahead (so w leaves at once)."""
        table, me = self.table, w.idx
        for hold, start, end in _spans(w, k, times, self.leave):
            if not table.admits(hold.resource, me, start, end):
                return False
            if hold.index == w.base + 1 and any(
                other.vehicle != me and other.key <= start for other in table.blocked[hold.resource]
            ):
                return False
        return True

    def _retime_stretch(self, w: Vehicle, k: int, times: Schedule) -> None:
        """Give w's stretch its new times and queue its holds again by their new start."""
        table, b = self.table, w.base
        spans = list(_spans(w, k, times, self.leave))
        for hold, _, _ in spans:
            table.remove(hold)
        for hold, start, end in spans:
            hold.start = hold.key = start
            hold.end = end
            table.add(hold)
        departs, arrives = times
        for n in range(k - b):
            w.depart[b + n] = departs[n]
            w.arrive[b + n + 1] = arrives[n]
        here = w.node_holds[b]
        here.end = node_hold_end(w.depart[b], w.arrive[b + 1], self.leave)
        table.ended(here)


def _earliest(w: Vehicle, graph: ClassGraph, k: int, now: float) -> Schedule | None:
    """The earliest departures of w from route indices b..k-1 (b its decision point) and
    arrivals at b+1..k, driving without waiting; None if that is not earlier than planned or
    misses w's planned departure from k (its unchanged rest must still follow)."""
    b = w.base
    depart = max(now, w.ready_at) + graph.turn(w.headings[b], w.headings[b + 1])
    if depart >= w.depart[b]:
        return None
    departs: list[float] = []
    arrives: list[float] = []
    for i in range(b + 1, k + 1):
        departs.append(depart)
        arrive = depart + graph.travel[(w.route[i - 1], w.route[i])]
        arrives.append(arrive)
        if i < len(w.route) - 1:
            depart = arrive + stay(w, graph, i)
    if k < len(w.route) - 1 and depart > w.depart[k]:
        return None
    return departs, arrives


def _spans(
    w: Vehicle, k: int, times: Schedule, leave: float
) -> Iterator[tuple[Hold, float, float]]:
    """(hold, new start, new end) of each hold of w's stretch b+1..k at `times` (the node
    hold at k keeps its end: w leaves k as planned; `leave` as in `plans.node_hold_end`)."""
    departs, arrives = times
    b = w.base
    for i in range(b + 1, k + 1):
        n = i - b - 1
        edge = w.edge_holds[i]
        assert edge is not None  # every step after the first has its segment hold
        yield edge, departs[n], arrives[n]
        node = w.node_holds[i]
        end = node_hold_end(departs[n + 1], arrives[n + 1], leave) if i < k else node.end
        yield node, departs[n], end
