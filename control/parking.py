"""Idle vehicles out of the way: park the ones that keep an order from being planned.

An idle vehicle (no order) holds its node until further notice, so an order whose goal, or a
one-lane passage on its way, is such a node finds no plan (`traffic.NoPlanError`) and would
wait forever. When that happens `TrafficLink.start` asks `IdleParking.clear_way`: it walks the
order's free-flow route (the shortest one, other vehicles ignored), finds the idle vehicles whose
node conflicts with it and asks for a `vehicle.park` job for each (the flush opens it as a move
to a park station, `control.persistence._open_job`; it is then driven like any order). The
order is planned again at every sync and starts once the way is clear.

Here only what happens in memory, under the controller's lock: which vehicles, which station,
and a per-vehicle rate limit. Docs: TRAFFIC_RESULTS.md "In control".
"""

import heapq
import logging
import math
from collections.abc import Callable, Collection, Iterable, Mapping
from dataclasses import dataclass, field
from typing import Any

from control.execution import LayoutIndex
from control.live import LiveVehicle
from control.traffic_support import AUTOMATIC
from traffic import TrafficManager
from traffic.sipp import ANY_HEADING, ClassGraph

logger = logging.getLogger(__name__)

PARK_EVERY = 30.0  # s before the same vehicle may be sent to park again (a refused request)
# s a vehicle whose order finds no plan counts as busy, not idle (it will leave by itself);
# after that it is stuck, e.g. on the goal of the very order that holds its own goal, and may
# be sent to park like an idle one (a load run's orders, each dispatched to the vehicle left
# on a drop station, waited for each other in pairs for good)
WAITING_FOR = 10.0


def choose_station(
    stations: Mapping[str, str], seconds: Mapping[str, float], unavailable: Collection[str]
) -> str | None:
    """The park station (id) whose node is nearest by `seconds` (node id -> travel seconds;
    missing or infinite: unreachable), of those whose node is not `unavailable`; ties go to
    the smaller station id."""
    options = []
    for station_id, node in stations.items():
        cost = seconds.get(node, math.inf)
        if node not in unavailable and math.isfinite(cost):
            options.append((cost, station_id))
    return min(options)[1] if options else None


def free_flow_route(graph: ClassGraph, start: int, goals: Iterable[int]) -> list[tuple[int, int]]:
    """The shortest route from `start` through `goals`, other vehicles ignored, as its steps
    (segment resource, node entered); empty when a goal cannot be reached. Follows the
    planner's own cached tables (exact travel times, turns included)."""
    steps: list[tuple[int, int]] = []
    here, key = start, ANY_HEADING
    for goal in goals:
        table = graph.to(goal)
        while here != goal:
            best: tuple[float, int, int, int] | None = None
            for node, segment, tau, node_key in graph.succ[here]:
                cost = graph.turn(key, node_key) + tau + table[graph.states[node][node_key]]
                if best is None or cost < best[0]:
                    best = (cost, node, segment, node_key)
            if best is None or not math.isfinite(best[0]) or len(steps) > graph.state_count:
                return []  # unreachable (a search never runs longer than the states)
            _, here, segment, key = best
            steps.append((segment, here))
    return steps


def nearest(
    graph: ClassGraph, start: int, targets: Collection[int], avoid: Collection[int] = ()
) -> dict[int, float]:
    """The nearest of `targets` from node `start`, with its travel seconds (turns ignored),
    entering no resource in `avoid` (where the waiting vehicle stands: a station behind it
    cannot be reached while it waits); all those at that same distance, or {} if none.

    A Dijkstra that stops at the first target: it only looks around the vehicle, however
    large the layout and however many park stations it has."""
    best = {start: 0.0}
    heap = [(0.0, start)]
    found: dict[int, float] = {}
    while heap:
        cost, node = heapq.heappop(heap)
        if found and cost > min(found.values()):
            break
        if cost > best[node]:
            continue
        if node in targets:
            found[node] = cost
            continue
        for other, segment, tau, _ in graph.succ[node]:
            if other in avoid or segment in avoid or cost + tau >= best.get(other, math.inf):
                continue
            best[other] = cost + tau
            heapq.heappush(heap, (cost + tau, other))
    return found


def is_idle(vehicle: LiveVehicle) -> bool:
    """No order, in automatic mode, online, not charging, no fatal error, nothing running."""
    state = vehicle.state
    return (
        vehicle.execution is None
        and vehicle.pk is not None
        and state is not None
        and str(state.operating_mode) in AUTOMATIC
        and vehicle.is_available  # online, localised, not charging, no fatal error
        and vehicle.is_idle
    )


@dataclass
class IdleParking:
    """Sends idle vehicles that stand in an order's way to a free park station."""

    request_job: Callable[[dict[str, Any]], None]  # a `vehicle.park` job for the flush
    # s an idle vehicle may stand off a park station (on a drop station, mid-aisle) before it
    # is sent to park unasked; 0: only when in an order's way (`park_stale`)
    park_after: float = 0.0
    every: float = PARK_EVERY
    sent: dict[str, tuple[float, str]] = field(default_factory=dict)  # name -> (when, node)
    # name -> when its order first found no plan (until it gets one)
    waiting: dict[str, float] = field(default_factory=dict)
    count: int = 0  # park requests made (for tests and the logs)
    idle_since: dict[str, float] = field(default_factory=dict)  # name -> idle off a station

    def failed(self, name: str, now: float) -> None:
        """`name` has an order that found no plan now: for WAITING_FOR s it is not idle."""
        self.waiting.setdefault(name, now)

    def planned(self, name: str) -> None:
        self.waiting.pop(name, None)

    def clear_way(
        self,
        manager: TrafficManager,
        index: LayoutIndex,
        mover: str,
        goals: list[str],
        vehicles: Mapping[str, LiveVehicle],
        now: float,
        reason: str,
    ) -> list[str]:
        """Ask to park every idle vehicle on `mover`'s free-flow route through `goals`;
        returns the names of those sent now."""
        self.failed(mover, now)
        if not index.parking:
            return []
        v = manager.vehicle(mover)
        layout = manager.layout
        start = v.route[v.passed]
        steps = free_flow_route(manager.graphs[v.cls], start, [layout.node(g) for g in goals])
        mover_stands = set(manager.conflicts.of(v.cls, start))
        way: set[int] = set()
        for segment, node in steps:
            way.update(manager.conflicts.of(v.cls, segment))
            way.update(manager.conflicts.of(v.cls, node))
        taken: set[str] | None = None
        sent = []
        for name, vehicle in vehicles.items():
            other = manager.vehicle(name)
            if other.route[-1] not in way or other.passed != len(other.route) - 1:
                continue  # not standing in the way (cheap first: most vehicles are not)
            if name == mover or other.static or not self._may_send(name, vehicle, now):
                continue
            if taken is None:
                taken = self.unavailable(manager, index, vehicles, steps, now)
            if self._send(manager, index, name, vehicle, taken, mover_stands, now, reason):
                sent.append(name)
        return sent

    def park_stale(
        self,
        manager: TrafficManager,
        index: LayoutIndex,
        vehicles: Mapping[str, LiveVehicle],
        busy: Collection[int],
        now: float,
    ) -> list[str]:
        """Send to park the vehicles that stood idle off a park station for `park_after` s
        with no order assigned (`busy`: vehicle pks that have one); returns their names.

        Vehicles left on a drop station hold it until they leave: every later order to that
        station first had to find no plan and park them (`clear_way`), which stretched the
        start of most orders in a load run's steady state."""
        if self.park_after <= 0 or not index.parking:
            return []
        layout = manager.layout
        park_nodes = {layout.index.get(n) for n in index.parking.values()}
        taken: set[str] | None = None
        sent = []
        for name, vehicle in vehicles.items():
            v = manager.vehicle(name)
            if (
                v.static
                or v.passed != len(v.route) - 1
                or v.route[-1] in park_nodes
                or vehicle.pk in busy
                or not is_idle(vehicle)
            ):
                self.idle_since.pop(name, None)
                continue
            since = self.idle_since.setdefault(name, now)
            if now - since < self.park_after or not self._may_send(name, vehicle, now):
                continue
            if taken is None:
                taken = self.unavailable(manager, index, vehicles, [], now)
            reason = f"idle for {now - since:.0f} s"
            if self._send(manager, index, name, vehicle, taken, (), now, reason):
                del self.idle_since[name]
                sent.append(name)
        return sent

    def _send(
        self,
        manager: TrafficManager,
        index: LayoutIndex,
        name: str,
        vehicle: LiveVehicle,
        taken: set[str],
        avoid: Collection[int],
        now: float,
        reason: str,
    ) -> bool:
        """Ask for a `vehicle.park` job to the nearest free park station (not in `taken`,
        reached without entering `avoid`); the station is taken from then on."""
        layout = manager.layout
        v = manager.vehicle(name)
        free = {layout.index[n] for n in index.parking.values() if n not in taken}
        found = nearest(manager.graphs[v.cls], v.route[-1], free, avoid)
        seconds = {layout.node_ids[n]: cost for n, cost in found.items()}
        station = choose_station(index.parking, seconds, taken)
        if station is None:
            logger.info("traffic: no free park station for %s (%s)", name, reason)
            return False
        taken.add(index.parking[station])
        self.sent[name] = (now, index.parking[station])
        self.count += 1
        self.request_job(
            {"kind": "vehicle.park", "vehicle": vehicle.pk, "station": station, "reason": reason}
        )
        logger.info("traffic: %s sent to park at %s (%s)", name, station, reason)
        return True

    def _may_send(self, name: str, vehicle: LiveVehicle, now: float) -> bool:
        last = self.sent.get(name)
        if last is not None and now - last[0] < self.every:
            return False  # asked already: the job is on its way (or was refused, try later)
        waiting = self.waiting.get(name)
        if waiting is not None and now - waiting < WAITING_FOR:
            return False  # its own order waits to start: it may leave by itself
        return is_idle(vehicle)

    def unavailable(
        self,
        manager: TrafficManager,
        index: LayoutIndex,
        vehicles: Mapping[str, LiveVehicle],
        steps: list[tuple[int, int]],
        now: float,
    ) -> set[str]:
        """Nodes no idle vehicle may be parked on now: held or reserved by anyone, the target
        of another park (asked for or driving), or on the way being cleared."""
        layout = manager.layout
        taken = {layout.node_ids[node] for _, node in steps}
        for node_id in index.parking.values():
            node = layout.index.get(node_id)
            if node is None or any(h.resource == node for h in manager.table.blocked[node]):
                taken.add(node_id)  # unknown to traffic, or a vehicle holds or reserved it
        taken |= {node for when, node in self.sent.values() if now - when < self.every}
        for vehicle in vehicles.values():
            execution = vehicle.execution
            if execution is not None and execution.kind == "park" and execution.route:
                taken.add(execution.route[-1])
        return taken
