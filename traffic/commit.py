"""Putting a searched path into the reservation table, and the checks around a search.

Split from `traffic.manager` (which prepares the searches): `_search` runs one, again at a
larger weight or without the congestion cost when it found no complete path; `_commit`
replaces a vehicle's unreleased steps with a new path's holds and releases what it can; `_fits`
re-checks a path searched while the table was open to other threads; `_remaining` is the time
a vehicle still drives to its decision point. `TrafficManager` inherits them.
"""

from __future__ import annotations

import functools
from collections.abc import Callable
from contextlib import AbstractContextManager

from traffic.aside import Lifelong
from traffic.congestion import FlowCost
from traffic.plans import NO_HOLD, Release, Vehicle, node_hold_end
from traffic.reservations import INF, Hold
from traffic.sipp import ClassGraph, Path


class Commit(Lifelong):
    """Committing paths to the table (a `TrafficManager` base class)."""

    _segment: dict[tuple[int, int], int]
    _length: dict[tuple[int, int], float]
    max_expansions: int
    weight: float
    quick_search: tuple[int, float] | None
    flow_costs: list[FlowCost] | None

    def _search(
        self,
        run: Callable[..., Path | None],
        unlocked: Callable[[], AbstractContextManager[object]] | None,
    ) -> Path | None:
        """`run` the search (`_bounded`); with `congestion`, a search that found no complete
        path is repeated without the cost (a cost may drop a state that a path needed, see
        `traffic.congestion`)."""
        path = self._bounded(run, unlocked)
        if (path is None or not path.complete) and self.flow_costs is not None:
            path = self._bounded(functools.partial(run, move_cost=None), unlocked) or path
        return path

    def _bounded(
        self,
        run: Callable[..., Path | None],
        unlocked: Callable[[], AbstractContextManager[object]] | None,
    ) -> Path | None:
        """`run` the search, and with `quick_search` once more at its larger weight if the
        first search found no complete path within its expansions."""
        if self.quick_search is None:
            return run(max_expansions=self.max_expansions, weight=self.weight, unlocked=unlocked)
        cap, fallback = self.quick_search
        path = run(max_expansions=cap, weight=self.weight, unlocked=unlocked)
        if path is None or not path.complete:
            again = run(max_expansions=self.max_expansions, weight=fallback, unlocked=unlocked)
            path = again or path
        return path

    def _fits(self, v: Vehicle, path: Path, since: int) -> bool:
        """Whether `path`, searched from table clock `since` on, still fits from `v`'s decision
        point: every step's segment and node hold inside a safe interval, and the start left
        before another vehicle's queued hold there (what the search checked, asked again of
        the lists that changed since)."""
        table, me, nodes = self.table, v.idx, path.nodes
        ends = self._node_ends(path)
        if table.changed_since(nodes[0], since) and ends[0] > table.first_other_start(nodes[0], me):
            return False
        for j in range(1, len(nodes)):
            enter, left = path.depart[j - 1], ends[j]
            segment = self._segment[(nodes[j - 1], nodes[j])]
            for resource, end in ((segment, path.arrive[j]), (nodes[j], left)):
                if table.changed_since(resource, since) and not table.admits(
                    resource, me, enter, end
                ):
                    return False
        return True

    def _node_ends(self, path: Path) -> list[float]:
        """When the hold on each node of `path` ends (`plans.node_hold_end`; inf at the last)."""
        last = len(path.nodes) - 1
        return [
            node_hold_end(path.depart[j], path.arrive[j + 1], self.leave) if j < last else INF
            for j in range(last + 1)
        ]

    def _remaining(self, v: Vehicle, graph: ClassGraph) -> float:
        """Seconds the vehicle still needs to its decision point, driving without waiting."""
        seconds = 0.0
        for i in range(v.passed, v.base):
            seconds += graph.turn(v.headings[i], v.headings[i + 1])
            seconds += graph.travel[(v.route[i], v.route[i + 1])]
        return seconds

    def _commit(
        self,
        v: Vehicle,
        path: Path,
        goals: list[tuple[int, float]],
        now: float,
        *,
        hold: bool = False,
    ) -> list[Release]:
        """Put `path` into the table from the vehicle's decision point, then release.

        A vehicle at the end of its route, or standing at the goal its base stops at, starts a
        new route (new `plan_id`); one still driving keeps its base and gets a new horizon.
        With `hold` the base will stop at the last goal (a refuge path, `traffic.aside`).
        """
        b = v.base
        table, conflicts = self.table, self.conflicts
        new = v.passed == b and (b == len(v.route) - 1 or b == v.hold_at)
        for i in range(len(v.route) - 1, b, -1):
            edge = v.edge_holds[i]
            if edge is not None:
                table.remove(edge)
            table.remove(v.node_holds[i])
        v.truncate(b)
        if new:
            v.restart(path.nodes[0])
            v.last_progress = now  # a new route: no progress owed on it yet (not stalled)
            b = 0
        ends = self._node_ends(path)
        v.node_holds[b].end = ends[0]
        table.ended(v.node_holds[b])
        for j in range(1, len(path.nodes)):
            i = b + j
            u, n = path.nodes[j - 1], path.nodes[j]
            seg = self._segment[(u, n)]
            dep, end = path.depart[j - 1], ends[j]
            edge = Hold(v.idx, seg, i, dep, path.arrive[j], conflicts.of(v.cls, seg))
            node = Hold(v.idx, n, i, dep, end, conflicts.of(v.cls, n))
            table.add(edge)
            table.add(node)
            v.append(
                n,
                path.arrive[j],
                path.depart[j],
                path.headings[j],
                (edge, node),
                self._length[(u, n)],
            )
        v.depart[b] = path.depart[0]
        v.goals = goals
        stops = [b + s for s in path.stops]
        v.stops = stops + [len(v.route) + 10**9] * (len(goals) - len(stops))
        v.complete = path.complete
        v.hold_at = stops[-1] if hold and path.complete and stops else NO_HOLD
        if b in stops[:1] and v.passed == b and not new:
            v.ready_at = max(v.ready_at, v.arrive[b] + goals[0][1])
        releases: list[Release] = []
        own = self._extend(v, now)
        if own is None and not new and b == len(v.route) - 1:
            # the last goal is served at the decision point: no base to extend, but the caller
            # must learn that the route ends there (an order update without a horizon)
            own = Release(v.name, v.plan_id, b, b)
        if own is not None:
            releases.append(own)
        releases.extend(self._wake(v.idx, now))
        return releases


def planning_state(v: Vehicle) -> tuple[object, ...]:
    """What a search of `v` starts from (a path searched unlocked is kept only if unchanged)."""
    return (v.plan_id, v.first_index, v.base, v.passed, len(v.route), v.static, v.ready_at,
            v.hold_at, v.route[v.base])  # fmt: skip
