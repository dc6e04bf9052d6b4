"""Traffic management in `control`: one `traffic.TrafficManager` per map, fed by state messages.

The link decides how far each vehicle's VDA 5050 base may reach (docs TRAFFIC.md §0): an order's
route is planned with the manager when the order starts, and each state message reports progress
(`on_progress`), which clears what the vehicle left and may release more base to it and to the
vehicles that waited for it. All of this runs in memory under the controller's lock: no database
and no Celery on the hot path. The driver asks `base_end` how far it may release; the rest of the
route goes out as horizon.

Vehicles in error (FATAL), in a manual mode or offline are static obstacles (`block`) until they
are back in automatic mode at a known node (`restore`). Route index i of a plan is node sequence
id 2·i, as everywhere in `control`. What part of a plan each order message carries is in
`control.traffic_windows`; how a route search lets the controller's lock go, in
`control.traffic_lock`.
"""

import logging
import time
from collections.abc import Callable, Iterable
from typing import Any

import vda5050
from control.execution import LayoutIndex, passed_index
from control.live import LiveVehicle
from control.parking import IdleParking
from control.session import Link
from control.traffic_lock import SearchLock
from control.traffic_support import (
    DEFAULT_CLASS,
    DWELL,
    Stats,
    Tracked,
    blocking_reason,
    envelope,
    layout_of,
    name,
    vehicle_class,
)
from control.traffic_views import TrafficViews
from control.traffic_windows import OrderWindows
from traffic import Goal, NoPlanError, Plan, ReleasePolicy, TrafficManager

logger = logging.getLogger(__name__)

UNPLANNED = "driving an order traffic did not plan"
NO_PLAN = "no plan"  # how problems that are only congestion begin (`problem_counts`)
# A search over 1,000 expansions is repeated at weight 2 (at most twice the earliest arrival):
# it bounds the time a plan holds the controller's lock in congestion; in the S1 benchmark it
# cut planning p95 by half with throughput unchanged (docs/TRAFFIC_RESULTS.md, third round).
QUICK_SEARCH = (1000, 2.0)
# A vehicle waiting at its decision point whose re-plans keep finding the same route (it
# waits behind a driving vehicle) is re-planned after 5, 10, 20, then every 40 s, not every
# 5 s: the tick's re-plans were the largest part of control's route planning under load
# (docs/LOAD.md, ninth round); the wait itself ends on the event path when the other moves.
REPLAN_BACKOFF = 8


class TrafficLink(OrderWindows, TrafficViews):
    """Traffic managers of every map and the vehicles they control (call under the lock)."""

    def __init__(
        self,
        fleet: Callable[[], Iterable[LiveVehicle]] = tuple,
        *,
        policy: ReleasePolicy | None = None,
        dwell: float = DWELL,
        park: Callable[[dict[str, Any]], None] | None = None,
        park_after: float = 0.0,
        lock: Any = None,
    ) -> None:
        self.fleet = fleet
        # The controller's lock (an RLock): a route search lets it go while it runs, so that
        # state messages are handled meanwhile (TrafficManager.unlocked, `let_go`).
        self.searches = SearchLock(lock)
        self._starting: set[str] = set()  # vehicles whose order start is being planned
        # Idle vehicles in the way of an order that finds no plan are sent to park through
        # `park` (a `vehicle.park` job for the flush); None: they stay (control/parking.py).
        # With `park_after` > 0 vehicles idle that long off a park station are parked too.
        self.parking = IdleParking(park, park_after) if park is not None else None
        self.policy = policy or ReleasePolicy()
        self.dwell = dwell
        self.managers: dict[str, TrafficManager] = {}
        self._indexes: dict[str, LayoutIndex] = {}
        self._layouts: object = None
        self.tracked: dict[str, Tracked] = {}
        self.stats = Stats()
        self.problems: dict[str, int] = {}
        self._stalled_logged: set[str] = set()  # stalled vehicles already logged

    # -- maps and vehicles ------------------------------------------------------------------

    def ensure(self, layouts: dict[str, LayoutIndex]) -> None:
        """Follow the controller's layouts (cheap when they are the same object as before)."""
        if layouts is not self._layouts:
            self._layouts = layouts
            self.set_layouts(layouts)

    def set_layouts(self, layouts: dict[str, LayoutIndex]) -> None:
        """Build a manager per map; a changed map starts afresh (its vehicles re-register)."""
        for map_id in list(self.managers):
            if layouts.get(map_id) != self._indexes.get(map_id):
                del self.managers[map_id], self._indexes[map_id]
                for name in [n for n, t in self.tracked.items() if t.map_id == map_id]:
                    del self.tracked[name]
        classes = [vehicle_class(v.factsheet) for v in self.fleet()]
        for map_id, index in layouts.items():
            if map_id not in self.managers:
                self.managers[map_id] = TrafficManager(
                    layout_of(index),
                    (envelope([DEFAULT_CLASS, *classes]),),
                    policy=self.policy,
                    quick_search=QUICK_SEARCH,
                    replan_to_base=False,  # a goal's actions cannot move onto the sent base
                    replan_backoff=REPLAN_BACKOFF,
                )
                if self.searches.lock is not None:
                    self.managers[map_id].unlocked = self.searches.let_go_if_allowed
                self._indexes[map_id] = index

    def problem_counts(self) -> tuple[int, int]:
        """(problems, order starts or re-adoptions that found no plan now and are tried
        again): the first are defects or bad input (progress beyond the base, a vehicle that
        cannot be placed, a failed tick), the second congestion."""
        no_plan = sum(n for p, n in self.problems.items() if p.startswith(NO_PLAN))
        return sum(self.problems.values()) - no_plan, no_plan

    def _count(self, problem: str) -> None:
        self.problems[problem] = self.problems.get(problem, 0) + 1
        if self.problems[problem] <= 10:
            logger.warning("traffic: %s", problem)

    def _register(self, vehicle: LiveVehicle, state: vda5050.State, now: float) -> Tracked | None:
        node = state.last_node_id
        map_id = state.agv_position.map_id if state.agv_position is not None else ""
        candidates = [map_id] if map_id in self.managers else list(self.managers)
        for candidate in candidates:
            manager = self.managers[candidate]
            if node not in manager.layout.index:
                continue
            try:
                manager.add_vehicle(name(vehicle), node, now)
            except ValueError as exc:
                self._count(f"cannot place {name(vehicle)}: {exc}")
                return None
            tracked = self.tracked[name(vehicle)] = Tracked(vehicle, candidate)
            tracked.note(now, f"registered at {node}")
            return tracked
        return None

    def _reset(self, tracked: Tracked, node: str, now: float) -> None:
        """Drop whatever plan the vehicle had: it stands at `node` (block, then restore)."""
        manager = self.managers[tracked.map_id]
        if node not in manager.layout.index:
            self._count(f"{name(tracked.vehicle)} reports unknown node {node!r}")
            return
        manager.block(name(tracked.vehicle), now)
        manager.restore(name(tracked.vehicle), node, now)
        tracked.note(now, f"reset at {node} (order {tracked.order_id})")
        tracked.order_id = None

    # -- hot path -----------------------------------------------------------------------------

    def observe(self, vehicle: LiveVehicle, state: vda5050.State, now: float) -> list[LiveVehicle]:
        """Take one state message; returns the other vehicles that got more base released."""
        started = time.perf_counter()
        try:
            return self._observe(vehicle, state, now)
        finally:
            self.stats.add(time.perf_counter() - started)

    def _observe(self, vehicle: LiveVehicle, state: vda5050.State, now: float) -> list[LiveVehicle]:
        tracked = self.tracked.get(name(vehicle))
        if tracked is None:
            if not state.last_node_id or blocking_reason(vehicle, state, now) is not None:
                return []
            tracked = self._register(vehicle, state, now)
            if tracked is None:
                return []
        manager = self.managers[tracked.map_id]
        reason = blocking_reason(vehicle, state, now)
        if reason is None and state.node_states and state.order_id != tracked.order_id:
            reason = UNPLANNED  # e.g. adopted after a restart
        if tracked.lost is not None and tracked.lost == state.order_id:
            if reason in (None, UNPLANNED):
                return self._readopt(tracked, state, now)
            return []
        if reason is not None or tracked.static is not None:
            return self._mode_change(tracked, reason, state, now)
        if tracked.order_id is None or state.order_id != tracked.order_id:
            return []
        v = manager.vehicle(name(vehicle))
        if (state.last_node_sequence_id or 0) // 2 - tracked.offset <= v.passed:
            return []  # no progress (most states): on_progress would do nothing either
        # (the previous order's sequence id, which a vehicle keeps until it passes the first
        # node of the new one, reads as index 0: nothing passed yet)
        passed = passed_index(state) - tracked.offset
        if not 0 <= passed < len(v.route) or manager.layout.node_ids[v.route[passed]] != (
            state.last_node_id
        ):
            return []  # not a node of this plan
        try:
            releases = manager.on_progress(name(vehicle), passed, now)
        except ValueError as exc:  # beyond its base: it drove what we never released
            self._count(
                f"{exc} (order {state.order_id}, sequence id {state.last_node_sequence_id}, "
                f"offset {tracked.offset}, plan {v.plan_id} of {len(v.route)} nodes; "
                f"{tracked.history(now)})"
            )
            return []
        me = name(vehicle)
        return [self.tracked[r.vehicle_id].vehicle for r in releases if r.vehicle_id != me]

    def _mode_change(
        self,
        tracked: Tracked,
        reason: str | None,
        state: vda5050.State,
        now: float,
        *,
        replan: bool = True,
    ) -> list[LiveVehicle]:
        manager = self.managers[tracked.map_id]
        me = name(tracked.vehicle)
        if reason is not None and tracked.static is None:
            replanned = manager.block(me, now, replan=replan)
            # What it still drives stays held (block keeps the released base); the rest of the
            # order waits for re-adoption at its decision point.
            driving = state is not None and bool(state.node_states) and state.order_id
            tracked.lost = tracked.order_id or (state.order_id if driving else None)
            tracked.static, tracked.order_id = reason, None
            tracked.note(now, f"blocked ({reason}), lost {tracked.lost}")
            logger.info("traffic: %s is a static obstacle (%s)", me, reason)
            return [self.tracked[n].vehicle for n in replanned if n in self.tracked]
        if reason is None and tracked.static is not None:
            if state.last_node_id not in manager.layout.index:
                return []
            try:
                manager.restore(me, state.last_node_id, now)
            except ValueError as exc:
                self._count(f"cannot restore {me}: {exc}")
                return []
            tracked.static, tracked.order_id = None, None
            tracked.note(now, f"restored at {state.last_node_id}")
            logger.info("traffic: %s is back under traffic control", me)
        return []

    def _readopt(self, tracked: Tracked, state: vda5050.State, now: float) -> list[LiveVehicle]:
        """Plan a lost order again once its vehicle waits at its decision point."""
        execution = tracked.vehicle.execution
        if execution is None or execution.vda_order_id != state.order_id:
            return []
        decision = execution.released_until
        if (state.last_node_sequence_id or 0) // 2 != decision or any(
            n.released and n.sequence_id > 2 * decision for n in state.node_states
        ):
            return []  # still driving its released base
        manager, me = self.managers[tracked.map_id], name(tracked.vehicle)
        if tracked.static is not None:
            try:
                manager.restore(me, state.last_node_id, now)
            except (ValueError, KeyError) as exc:
                self._count(f"cannot restore {me}: {exc!r}")
                return []
            tracked.static = None
        goals = [execution.route[i] for i in execution.stop_indices if i > decision]
        if goals:
            try:
                manager.plan(me, [Goal(g, self.dwell) for g in goals], now)
            except NoPlanError as exc:
                self._count(f"{NO_PLAN} to re-adopt {state.order_id}: {exc}")
                return []
        tracked.order_id, tracked.lost, tracked.offset = state.order_id, None, decision
        v = manager.vehicle(me)
        tracked.note(
            now, f"re-adopted {state.order_id} at {decision}: plan {v.plan_id} base {v.base}"
        )
        logger.info("traffic: %s re-adopted %s at route index %d", me, state.order_id, decision)
        return []

    def lost(self, vehicle: LiveVehicle, order_id: str) -> bool:
        """Whether `order_id` waits for re-adoption (the driver releases nothing meanwhile)."""
        tracked = self.tracked.get(name(vehicle))
        return tracked is not None and tracked.lost == order_id

    # -- orders -------------------------------------------------------------------------------

    def start(
        self, vehicle: LiveVehicle, order_id: str, map_id: str, goals: list[str], now: float
    ) -> Plan | None:
        """Plan a new order through `goals` from where the vehicle stands; None: not now."""
        tracked = self.tracked.get(name(vehicle))
        state = vehicle.state
        if tracked is None or tracked.static is not None or state is None:
            return None
        if tracked.map_id != map_id:
            self._count(f"{name(vehicle)} is on map {tracked.map_id}, order is on {map_id}")
            return None
        if name(vehicle) in self._starting:
            return None  # another thread is planning its start (the lock is let go meanwhile)
        manager = self.managers[map_id]
        v = manager.vehicle(name(vehicle))
        here = manager.layout.node_ids[v.route[v.passed]]
        if v.passed != len(v.route) - 1 or here != state.last_node_id:
            self._reset(tracked, state.last_node_id, now)
        self._starting.add(name(vehicle))
        try:
            with self.searches.searches_let_go():
                plan = manager.plan(name(vehicle), [Goal(g, self.dwell) for g in goals], now)
        except (NoPlanError, KeyError) as exc:
            self._count(f"{NO_PLAN} for {order_id}: {exc!r}")
            if isinstance(exc, NoPlanError) and self.parking is not None:
                self._clear_way(self.parking, tracked, order_id, goals, now)
            return None
        finally:
            self._starting.discard(name(vehicle))
        if (
            self.managers.get(map_id) is not manager
            or self.tracked.get(name(vehicle)) is not tracked
        ):
            # the layout changed while the lock was let go: that manager is gone
            return None
        if self.parking is not None:
            self.parking.planned(name(vehicle))
        tracked.order_id, tracked.lost, tracked.offset = order_id, None, 0
        tracked.note(now, f"started {order_id}: plan {plan.plan_id} base {plan.base_end}")
        return plan

    def _clear_way(
        self, parking: IdleParking, tracked: Tracked, order_id: str, goals: list[str], now: float
    ) -> None:
        """Send the idle vehicles standing on the order's free-flow route to park."""
        on_map = {n: t.vehicle for n, t in self.tracked.items() if t.map_id == tracked.map_id}
        parking.clear_way(
            self.managers[tracked.map_id],
            self._indexes[tracked.map_id],
            name(tracked.vehicle),
            goals,
            on_map,
            now,
            reason=f"in the way of order {order_id}",
        )

    def park_stale(self, busy: set[int], now: float) -> None:
        """Send vehicles idle off a park station for `park_after` s to park (none with an
        order assigned: `busy` holds their pks); see `IdleParking.park_stale`."""
        if self.parking is None or self.parking.park_after <= 0:
            return
        for map_id, manager in self.managers.items():
            on_map = {n: t.vehicle for n, t in self.tracked.items() if t.map_id == map_id}
            self.parking.park_stale(manager, self._indexes[map_id], on_map, busy, now)

    def ended(self, vehicle: LiveVehicle, now: float) -> None:
        """The vehicle's order is over (finished, failed, cancelled): forget the rest of it."""
        tracked = self.tracked.get(name(vehicle))
        if tracked is not None:
            tracked.lost = None
        if tracked is None or tracked.order_id is None:
            return
        tracked.note(now, f"ended {tracked.order_id}")
        state = vehicle.state
        manager = self.managers[tracked.map_id]
        v = manager.vehicle(name(vehicle))
        tracked.order_id = None
        if v.passed != len(v.route) - 1 and state is not None and tracked.static is None:
            self._reset(tracked, state.last_node_id, now)  # stopped mid-route: free the rest

    def controls(self, vehicle: LiveVehicle, order_id: str) -> bool:
        """Whether the traffic manager releases `order_id` of this vehicle."""
        tracked = self.tracked.get(name(vehicle))
        return tracked is not None and tracked.order_id == order_id

    def tick(self, now: float) -> None:
        """About once a second: block vehicles that went offline, re-time and re-plan."""
        # Vehicles that went offline are blocked first, and those queued behind them
        # re-planned once afterwards: when the broker goes away the whole fleet goes offline
        # at once, and re-planning after each block re-planned vehicles about to be blocked
        # too (1,000 vehicles held the lock for half a minute).
        behind: dict[str, Tracked] = {}
        for tracked in list(self.tracked.values()):
            vehicle = tracked.vehicle
            if tracked.static is None and vehicle.session.link(now) is not Link.ONLINE:
                state: Any = vehicle.state
                for other in self._mode_change(tracked, "offline", state, now, replan=False):
                    behind[name(other)] = self.tracked[name(other)]
        for queued_name, queued in behind.items():
            if queued.static is None and self.tracked.get(queued_name) is queued:
                with self.searches.searches_let_go():
                    self.managers[queued.map_id].replan(queued_name, now)
        for map_id, manager in list(self.managers.items()):
            try:
                with self.searches.searches_let_go():  # re-plans: state messages go on meanwhile
                    manager.tick(now)
            except Exception as exc:  # the order sync after it must go on (starts, resends)
                self._count(f"traffic tick failed on map {map_id}: {exc!r}")
