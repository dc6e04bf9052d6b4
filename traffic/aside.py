"""Lifelong task streams on dense layouts: refuges after the goal and stepping aside (opt-in).

Both mechanisms are off by default (`TrafficManager(goal_refuge=..., step_aside=...)`); the LoRR
benchmark (S2) turns them on. They change which plans are made, never how plans are executed:
every plan is still a full SIPP plan against the reservation table ending in a hold for good, so
the ADG release guarantee (no collision, acyclic waits) is untouched.

- **Goal refuge.** A plan that ends with a hold for good at its goal fails whenever the goal is
  somebody's refuge, or when staying there would block others. With `goal_refuge` a plan only
  visits its last goal and goes on to the nearest node where the vehicle may stay for good (its
  refuge, `traffic.sipp.search(refuge=True)`). The base stops at the goal: the vehicle's next task
  is planned from there (a new route, `plan_id` + 1) and replaces the way to the refuge; if that
  plan fails the caller sends the vehicle on to its reserved refuge with `proceed`. `tick()` sends
  on a vehicle left standing at its goal for `replan_after` seconds (the caller forgot).
- **Step aside.** When a plan fails, vehicles standing for good (at the end of their route, no
  plan) on its goal or on its free-flow route are the usual reason on a dense layout. With
  `step_aside` each of them (at most `ASIDE_LIMIT`) is sent to the nearest node off that route
  where it may stay, then the plan is tried once more. A vehicle sent aside keeps no goals; its
  caller plans its own task again when it reports the end of its route.
- **Late plans** (`_late`, for `improve_budget`): the vehicles whose plan reaches their next
  goal much later than driving alone would, which `tick()` re-plans in turn.
"""

from __future__ import annotations

import random

from traffic.execution import Execution
from traffic.layout import Layout
from traffic.plans import NO_HOLD, Release, Vehicle
from traffic.reservations import INF
from traffic.sipp import ClassGraph, Path, search

ASIDE_LIMIT = 4  # vehicles sent aside for one failed plan
ASIDE_EXPANSIONS = 5_000  # a nearby refuge or none
TRAFFIC_SOURCES = 500  # BFS trees sampled for the through-traffic estimate on large layouts


def through_traffic(layout: Layout, *, seed: int = 0) -> list[float]:
    """Per node, the share (0..1 of the busiest) of shortest routes that pass or end there.

    One BFS tree per source node (a sample of `TRAFFIC_SOURCES` on large layouts); a node counts
    the routes of its subtree. A refuge on a busy node blocks many later plans.
    """
    count = layout.node_count
    adjacent: list[list[int]] = [[] for _ in range(count)]
    for edge in layout.edges:
        adjacent[edge.start].append(edge.end)
    sources = list(range(count))
    if count > TRAFFIC_SOURCES:
        sources = random.Random(seed).sample(sources, TRAFFIC_SOURCES)  # noqa: S311
    total = [0.0] * count
    for source in sources:
        parent = [-2] * count
        parent[source] = -1
        order = [source]
        for n in order:
            for w in adjacent[n]:
                if parent[w] == -2:
                    parent[w] = n
                    order.append(w)
        below = [1] * count
        for n in reversed(order):
            total[n] += below[n]
            if parent[n] >= 0:
                below[parent[n]] += below[n]
    busiest = max(total, default=0.0) or 1.0
    return [t / busiest for t in total]


class Lifelong(Execution):
    """`proceed`, the goal-hold safety net and stepping aside (a `TrafficManager` base class)."""

    graphs: list[ClassGraph]
    replan_after: float
    improve_slack: float
    refuge_cost: list[float] | None

    def _commit(  # pragma: no cover (the manager's)
        self,
        v: Vehicle,
        path: Path,
        goals: list[tuple[int, float]],
        now: float,
        *,
        hold: bool = False,
    ) -> list[Release]:
        raise NotImplementedError

    def proceed(self, vehicle_id: str, now: float) -> list[Release]:
        """Let a vehicle standing at its goal drive on to its refuge (no next task planned)."""
        v = self.vehicle(vehicle_id)
        if v.hold_at == NO_HOLD:
            return []
        v.hold_at = NO_HOLD
        own = self._extend(v, now)
        return ([own] if own is not None else []) + self._wake(v.idx, now)

    def held_at_goal(self, vehicle_id: str) -> bool:
        """Whether the vehicle stands at the goal its base stops at, its refuge still ahead."""
        v = self.vehicle(vehicle_id)
        return v.passed == v.base == v.hold_at < len(v.route) - 1

    def _proceed_held(self, now: float) -> list[Release]:
        """Safety net: send on vehicles left at their goal for `replan_after` seconds."""
        releases: list[Release] = []
        for v in self._vehicles:
            if (
                v.hold_at != NO_HOLD
                and v.passed == v.base == v.hold_at < len(v.route) - 1
                and now - v.last_progress >= self.replan_after
            ):
                releases.extend(self.proceed(v.name, now))
        return releases

    # -- stepping aside -----------------------------------------------------------------------

    def _clear_way(self, v: Vehicle, goals: list[tuple[int, float]], now: float) -> list[Release]:
        """Send vehicles standing for good on the goals or the free-flow route aside."""
        route = self._free_flow_nodes(v, goals)
        avoid = set(route)
        releases: list[Release] = []
        moved: set[int] = set()
        for n in route:
            for hold in self.table.blocked[n]:
                other = self._vehicles[hold.vehicle]
                if (
                    hold.vehicle == v.idx
                    or hold.vehicle in moved
                    or hold.end != INF
                    or not hold.released
                    or other.static
                    or other.passed != len(other.route) - 1
                ):
                    continue
                moved.add(hold.vehicle)
                releases.extend(self._step_aside(other, avoid, now))
                if len(moved) >= ASIDE_LIMIT:
                    return releases
        return releases if moved else []

    def _step_aside(self, v: Vehicle, avoid: set[int], now: float) -> list[Release]:
        """Plan a vehicle standing at its route end to the nearest refuge outside `avoid`."""
        here = v.route[-1]
        deadline = self.table.first_other_start(here, v.idx)
        path = search(
            self.graphs[v.cls],
            self.table,
            v.idx,
            here,
            v.headings[-1],
            max(now, v.ready_at),
            deadline,
            [(here, 0.0)],
            max_expansions=ASIDE_EXPANSIONS,
            refuge=True,
            avoid=avoid,
            refuge_cost=self.refuge_cost,
            leave=self.leave,
        )
        if path is None or len(path.nodes) == 1:
            return []
        return self._commit(v, path, [(here, 0.0)], now)

    def _free_flow_nodes(self, v: Vehicle, goals: list[tuple[int, float]]) -> list[int]:
        """The nodes of the quickest route through `goals` with nobody else on the layout."""
        graph = self.graphs[v.cls]
        node, key = v.route[v.base], v.headings[v.base]
        nodes = [node]
        for goal, _ in goals:
            table = graph.to(goal)
            for _ in range(self.layout.node_count):
                if node == goal:
                    break
                options = [
                    (graph.turn(key, w_key) + tau + table[graph.states[w][w_key]], w, w_key)
                    for w, _, tau, w_key in graph.succ[node]
                ]
                if not options:
                    break
                cost, node, key = min(options)
                if cost == INF:
                    break
                nodes.append(node)
        return nodes

    def _late(self, now: float) -> list[int]:
        """Vehicles whose plan reaches its next goal more than `improve_slack` s later than
        from their decision point alone on the layout, latest first (not re-planned within
        `replan_after`)."""
        late: list[tuple[float, int]] = []
        for v in self._vehicles:
            if v.static or now - v.replanned_at < self.replan_after:
                continue
            b, last = v.base, len(v.route) - 1
            stop = next((s for s in v.stops if b < s <= last), -1)
            if stop < 0:
                continue
            goal = v.route[stop]
            graph = self.graphs[v.cls]
            alone = graph.cost_to(graph.to(goal), v.route[b], v.headings[b])
            lateness = v.arrive[stop] - max(now, v.arrive[b]) - alone
            if lateness > self.improve_slack:
                late.append((-lateness, v.idx))
        late.sort()
        return [idx for _, idx in late]


__all__ = ["ASIDE_LIMIT", "Lifelong"]
