"""The traffic manager: plans routes with SIPP and releases them step by step (ADG execution).

Call pattern (all in the control process, under its lock):

- `add_vehicle(id, node, now)` once per vehicle: it stands there, holding the node until planned;
- `plan(id, goals, now)` for a transport order: a timed route through the goals; the vehicle's
  VDA 5050 order is `plan.nodes` (route index i has sequence id 2·i), released up to
  `plan.releases[...].base_end`, the rest horizon;
- `on_progress(id, passed_index, now)` for every state message where lastNodeSequenceId moved:
  clears what the vehicle left and returns the base extensions (this vehicle's and any vehicle
  that was waiting for it), each to be sent as an order update. Costs microseconds; under
  the opt-in grid rules (S2) also `on_leave(id, now)` when the vehicle drives off its node;
- `replan(id, now)` re-plans the unreleased part (the base is irrevocable), e.g. after a delay;
- `park(id, now)` sends a vehicle without a task to the nearest free parking node;
- `block(id, now)` / `restore(...)` make a vehicle in error, manual mode or offline a static
  obstacle and back; `waiting_for(id)` tells the UI whom a vehicle waits for.

Step i of a route (i >= 1) is the move from node i-1 to node i: it holds the segment and node i.
The last node is held until the next plan. Clearing and base release (`on_progress`) live in
`traffic.execution`, the queries and `block`/`restore` in `traffic.queries`, the opt-in
lifelong mechanisms (`proceed`, stepping aside) in `traffic.aside`.
"""

from __future__ import annotations

import functools
from collections.abc import Callable, Sequence
from contextlib import AbstractContextManager
from dataclasses import replace

from traffic.aside import through_traffic
from traffic.commit import Commit, planning_state
from traffic.congestion import FlowCost
from traffic.footprint import ConflictSets, VehicleClass
from traffic.layout import Layout
from traffic.plans import GRID_LEAVE, Goal, Plan, Release, ReleasePolicy, Vehicle
from traffic.reservations import INF, Hold, ReservationTable
from traffic.sipp import ANY_HEADING, ClassGraph, Path, heading_key, search
from traffic.timing import lower_bounds, propagate

__all__ = ["Goal", "NoPlanError", "Plan", "Release", "ReleasePolicy", "TrafficManager"]


class NoPlanError(Exception):
    """No collision-free route to the goals exists now (try again later, or park).

    `releases`: base extensions made on the way (vehicles sent aside), to be sent all the same.
    """

    def __init__(self, message: str, releases: Sequence[Release] = ()) -> None:
        super().__init__(message)
        self.releases = tuple(releases)


class TrafficManager(Commit):
    """Plans, reservations and base releases for every vehicle of one layout.

    Built in layers: the queries (`waiting_for`, `wait_cycles`, `stalled`, ...) and
    `block`/`restore` (`traffic.queries`), clearing and base release (`on_progress`,
    `traffic.execution`), the lifelong mechanisms (`traffic.aside`), and here planning and
    `tick`.
    """

    def __init__(
        self,
        layout: Layout,
        classes: Sequence[VehicleClass] = (VehicleClass(),),
        *,
        policy: ReleasePolicy | None = None,
        conflicts: ConflictSets | None = None,
        max_expansions: int = 200_000,
        weight: float = 1.0,
        replan_after: float = 5.0,
        retime_slack: float = 2.0,
        retime_growth: float = 0.0,
        quick_search: tuple[int, float] | None = None,
        goal_refuge: bool = False,
        step_aside: bool = False,
        refuge_penalty: float = 0.0,
        replan_to_base: bool = True,
        improve_budget: int = 0,
        improve_slack: float = 2.0,
        replan_backoff: int = 1,
        switching: bool = False,
        switch_push: float = 10.0,
        switch_steps: int = 16,
        congestion: tuple[float, float] | None = None,
        grid_rules: bool = False,
    ) -> None:
        self.layout = layout
        # a re-plan may serve the next goal at the decision point (the route then ends or
        # turns there); control turns it off: VDA 5050 cannot add a goal's actions to a node
        # already sent as base, so such a re-plan is dropped and the old plan kept
        self.replan_to_base = replan_to_base
        self.classes = tuple(classes)
        self.policy = policy or ReleasePolicy()
        # opt-in, grid rules (LoRR, S2): cells instead of footprints, and a node is held
        # until `GRID_LEAVE` s after its vehicle leaves it (`on_leave`), not until the vehicle
        # reaches the next node: a vehicle may follow one cell behind another
        self.leave = GRID_LEAVE if grid_rules else -1.0
        cells = ConflictSets.cells if grid_rules else ConflictSets
        self.conflicts = conflicts or cells(layout, self.classes)
        self.graphs = [ClassGraph(layout, c) for c in self.classes]
        self.table = ReservationTable(layout.resource_count)
        self.max_expansions = max_expansions
        self.weight = weight  # heuristic weight of SIPP (1: earliest arrival)
        self.replan_after = replan_after  # s at a decision point before tick() re-plans
        self.retime_slack = retime_slack  # s a plan may run early before tick() re-times it
        # a vehicle s seconds without progress is re-timed growth·s past its earliest departure
        # (when more than the slack): fewer pushes of long waits (`timing.lower_bounds`)
        self.retime_growth = retime_growth
        # (expansions, weight): a search that needs more expansions than that at `weight` is
        # repeated with the larger weight (near-greedy), which bounds the planning-time tail
        # in congestion at the price of a later arrival for those few plans
        self.quick_search = quick_search
        # opt-in for lifelong task streams (`traffic.aside`): a plan visits its last goal and
        # goes on to a refuge, its base stopping at the goal until the next plan or `proceed`
        self.goal_refuge = goal_refuge
        # opt-in: a plan that fails first sends vehicles standing for good on its goal or its
        # free-flow route aside (`traffic.aside`), then is tried once more
        self.step_aside = step_aside
        # s a refuge on the busiest node costs (scaled by its through traffic): refuges
        # off the main routes block fewer later plans
        self.refuge_cost = (
            [refuge_penalty * share for share in through_traffic(layout)]
            if refuge_penalty > 0 and (goal_refuge or step_aside)
            else None
        )
        # opt-in (lifelong task streams): per tick, up to `improve_budget` vehicles whose plan
        # reaches their next goal more than `improve_slack` s later than driving alone would
        # are re-planned too, not only those waiting at their decision point (a detour or wait
        # that earlier plans forced may have opened up since)
        self.improve_budget = improve_budget
        self.improve_slack = improve_slack
        # a waiting vehicle whose re-plans kept its route k times in a row is re-planned again
        # only after replan_after · 2^k s, at most · `replan_backoff` (1: never later), until it
        # moves on or gets a new plan: control's tick spent its re-plans on vehicles that wait
        # behind a driving vehicle and find the same route each time
        self.replan_backoff = replan_backoff
        self._unchanged: dict[int, tuple[int, int, int]] = {}  # idx -> (count, passed, plan)
        self.replans = self.replans_unchanged = 0  # the tick's re-plans of waiting vehicles
        # opt-in: a vehicle waiting at its decision point behind a late vehicle's unreleased
        # holds may go ahead of it over a stretch of at most `switch_steps` steps, pushing the
        # late one's plan back by at most `switch_push` s (`traffic.switching`)
        self.switching = switching
        self.switch_push = switch_push
        self.switch_steps = switch_steps
        self.switches = self.switch_pushes = self.switches_dropped = 0
        # opt-in: (against, through) s per planned step of the others' remaining routes the
        # other way along a move's edge, and into its end node (`traffic.congestion`)
        self.flow_costs = (
            [FlowCost(layout, g, against=congestion[0], through=congestion[1]) for g in self.graphs]
            if congestion is not None
            else None
        )
        self._vehicles: list[Vehicle] = []
        self._index: dict[str, int] = {}
        self._waiters: dict[int, set[int]] = {}
        self._segment = {
            (e.start, e.end): layout.segment_resource(i) for i, e in enumerate(layout.edges)
        }
        self._length = {(e.start, e.end): e.length for e in layout.edges}
        # Set by a caller that plans under a lock of its own (control): the search loop then
        # runs inside `unlocked()`, which lets the lock go, so that other threads' state
        # messages are handled meanwhile; its path is checked once the lock is back and
        # searched again, held, from the current state if the vehicle itself changed
        # (`searches_moved`) or the table changed where the path goes (`searches_repeated`
        # counts both).
        self.unlocked: Callable[[], AbstractContextManager[object]] | None = None
        self.searches_repeated = 0
        self.searches_moved = 0  # of those, because the vehicle itself changed meanwhile

    # -- fleet ------------------------------------------------------------------------------

    def add_vehicle(
        self,
        vehicle_id: str,
        node: str,
        now: float,
        *,
        heading: float | None = None,
        vehicle_class: int = 0,
    ) -> None:
        """Register a vehicle standing at `node` (it holds the node until it gets a plan)."""
        if vehicle_id in self._index:
            raise ValueError(f"vehicle {vehicle_id} is already known")
        n = self.layout.node(node)
        idx = len(self._vehicles)
        if any(h.vehicle != idx for h in self.table.blocked[n]):
            raise ValueError(f"node {node} is reserved by another vehicle")
        key = ANY_HEADING if heading is None else heading_key(heading)
        v = Vehicle(vehicle_id, idx, vehicle_class, n, key, now)
        hold = Hold(idx, n, 0, now, INF, self.conflicts.of(vehicle_class, n))
        self.table.add_released(hold)
        v.node_holds = [hold]
        self._vehicles.append(v)
        self._index[vehicle_id] = idx

    @property
    def vehicle_ids(self) -> list[str]:
        """Every registered vehicle."""
        return [v.name for v in self._vehicles]

    # -- planning -----------------------------------------------------------------------------

    def plan(
        self, vehicle_id: str, goals: Sequence[Goal] | str, now: float, *, partial: bool = False
    ) -> Plan:
        """Plan `vehicle_id` through `goals` (a node id, or goals with dwell times).

        A vehicle at the end of its route gets a new plan (new `plan_id`, route index 0 is where
        it stands); a vehicle still driving keeps its released base and gets a new horizon from
        its decision point (when the last goal is served at the decision point the horizon is
        empty, and `plan.releases` says so with its `base_end == route_end`). With `partial`
        (single goal only), an unreachable goal yields a plan to the nearest node where the
        vehicle may wait (`plan.complete` is False).
        Raises NoPlanError when no plan exists now.
        """
        v = self.vehicle(vehicle_id)
        wanted = [Goal(goals)] if isinstance(goals, str) else list(goals)
        if not wanted:
            raise ValueError("at least one goal is needed")
        if partial and len(wanted) > 1:
            raise ValueError("partial plans take a single goal")
        targets = [(self.layout.node(g.node), g.dwell) for g in wanted]
        plan = self._plan(v, targets, now, partial)
        moved: list[Release] = []
        if plan is None and self.step_aside and not partial:
            moved = self._clear_way(v, targets, now)
            if moved:
                plan = self._plan(v, targets, now, partial)
        if plan is None:
            raise NoPlanError(f"no route for {vehicle_id} to {wanted[-1].node} now", moved)
        return replace(plan, releases=(*moved, *plan.releases)) if moved else plan

    def replan(self, vehicle_id: str, now: float) -> Plan | None:
        """Re-plan the unreleased rest of the route to the same goals; None if kept as it was.

        The route may then end at the decision point (see `plan`): the caller must treat the
        vehicle as having reached its route end there.
        """
        v = self.vehicle(vehicle_id)
        v.replanned_at = now
        remaining = [g for g, stop in zip(v.goals, v.stops, strict=True) if stop > v.base]
        if not remaining or v.static:
            return None
        partial = not v.complete and len(remaining) == 1
        return self._plan(v, remaining, now, partial, to_base=self.replan_to_base, same_plan=True)

    def park(self, vehicle_id: str, now: float, *, candidates: int = 8) -> Plan:
        """Send a vehicle to the nearest parking node where it may stay (NoPlanError if none)."""
        v = self.vehicle(vehicle_id)
        here = v.route[v.base]
        graph = self.graphs[v.cls]
        if here in self.layout.parking and v.base == len(v.route) - 1:
            return v.snapshot(self.layout, ())
        nearest = sorted(self.layout.parking, key=lambda p: (graph.to(p)[here], p))
        for p in nearest[:candidates]:
            if graph.to(p)[here] == INF:
                break
            plan = self._plan(v, [(p, 0.0)], now, False, refuge=False)
            if plan is not None:
                return plan
        raise NoPlanError(f"no free parking node reachable for {vehicle_id}")

    def _plan(
        self,
        v: Vehicle,
        goals: list[tuple[int, float]],
        now: float,
        partial: bool,
        *,
        refuge: bool | None = None,
        to_base: bool = True,
        same_plan: bool = False,
    ) -> Plan | None:
        """Search and commit; with `same_plan` (a re-plan, whose goals are the rest of the
        vehicle's plan) nothing is committed if another thread gave it a new plan meanwhile."""
        if v.static:
            return None
        refuge = self.goal_refuge if refuge is None else refuge
        if self.unlocked is None:
            path = self._search(self._searcher(v, goals, now, partial, refuge), None)
        else:
            before, since = planning_state(v), self.table.clock
            path = self._search(self._searcher(v, goals, now, partial, refuge), self.unlocked)
            moved = path is not None and planning_state(v) != before
            if moved or (path is not None and not self._fits(v, path, since)):
                # The vehicle (its base was extended, it was blocked or planned by another
                # thread) or the table changed under the search: again, held this time, from
                # the vehicle and the table as they are now. (Searching again from the old
                # start once made a route that went from a node to itself.)
                self.searches_repeated += 1
                self.searches_moved += moved
                if v.static or (same_plan and v.plan_id != before[0]):
                    # (a re-plan of an order that ended meanwhile gave the idle vehicle a
                    # route to the old goals, its base held against everyone until its next)
                    return None
                path = self._search(self._searcher(v, goals, now, partial, refuge), None)
        if path is None or (not to_base and path.stops[:1] == [0]):
            return None
        releases = self._commit(v, path, goals, now, hold=refuge)
        return v.snapshot(self.layout, releases)

    def _searcher(
        self, v: Vehicle, goals: list[tuple[int, float]], now: float, partial: bool, refuge: bool
    ) -> Callable[..., Path | None]:
        """The search of `v`'s route from its decision point as it is now (`_search` runs it)."""
        graph = self.graphs[v.cls]
        b = v.base
        start = v.route[b]
        t0 = max(now, v.ready_at) if v.passed == b else now + self._remaining(v, graph)
        deadline = self.table.first_other_start(start, v.idx)
        args = (graph, self.table, v.idx, start, v.headings[b], t0, deadline, goals)
        flow = self.flow_costs[v.cls] if self.flow_costs is not None else None
        return functools.partial(
            search, *args, partial=partial, refuge=refuge, refuge_cost=self.refuge_cost,
            move_cost=flow.costs(self._vehicles, v, now) if flow is not None else None,
            leave=self.leave,
        )  # fmt: skip

    # -- housekeeping -------------------------------------------------------------------------

    def tick(self, now: float, *, budget: int = 2) -> list[Release]:
        """Housekeeping at about 1 Hz (milliseconds): re-time, then re-plan waiting vehicles.

        Re-timing pushes planned times that delays made too early (`traffic.timing`); then up to
        `budget` vehicles stopped at their decision point for `replan_after` seconds get their
        unreleased steps re-planned, which may let them pass ahead of a late vehicle.
        Every waiting vehicle's base is re-checked first (microseconds each): a safety net so
        that a wake-up missed by the event path costs a vehicle at most one tick, and where
        switches are tried (`switching`; never on a state message, `traffic.execution`). A re-plan
        that ends a route where the vehicle stands returns its release with `base_end ==
        route_end`: its route (order) is done there.
        """
        releases: list[Release] = self._proceed_held(now) if self.goal_refuge else []
        for v in self._vehicles:
            if v.blocked_by >= 0 and v.base == v.passed and not v.static:
                release = self._extend(v, now)
                if release is not None:
                    releases.append(release)
        pushes = []
        for v in self._vehicles:
            bound = lower_bounds(v, self.graphs[v.cls], now, self.retime_slack, self.retime_growth)
            if bound is not None:
                pushes.append((bound[0], v.idx, bound[1]))
        propagate(self._vehicles, self.table, self.graphs, pushes, self.leave)
        waiting = sorted(
            (v.blocked_since, v.idx)
            for v in self._vehicles
            if v.blocked_by >= 0
            and v.base == v.passed
            and now - v.blocked_since >= self.replan_after
            and now - v.replanned_at >= self._replan_interval(v)
        )
        for _, idx in waiting[:budget]:
            releases.extend(self._replan_waiting(self._vehicles[idx], now))
        if self.improve_budget > 0:
            for idx in self._late(now)[: self.improve_budget]:
                plan = self.replan(self._vehicles[idx].name, now)
                if plan is not None:
                    releases.extend(plan.releases)
        return releases

    def _replan_interval(self, v: Vehicle) -> float:
        """Seconds between the tick's re-plans of waiting vehicle `v` (see `replan_backoff`)."""
        streak = self._unchanged.get(v.idx)
        if streak is None:
            return self.replan_after
        count, passed, plan_id = streak
        if (passed, plan_id) != (v.passed, v.plan_id):  # it moved on: a fresh start
            del self._unchanged[v.idx]
            return self.replan_after
        return self.replan_after * min(1 << count, self.replan_backoff)

    def _replan_waiting(self, v: Vehicle, now: float) -> list[Release]:
        """Re-plan a vehicle waiting at its decision point; count whether its route stayed."""
        before = v.route[v.base :]
        plan = self.replan(v.name, now)
        self.replans += 1
        if plan is None or v.route[v.base :] == before:
            self.replans_unchanged += 1
            count = min(self._unchanged.get(v.idx, (0, 0, 0))[0] + 1, 16)
            self._unchanged[v.idx] = (count, v.passed, v.plan_id)
        else:
            self._unchanged.pop(v.idx, None)
        return list(plan.releases) if plan is not None else []
