"""What the traffic manager hands out (goals, plans, releases) and what it keeps per vehicle."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field

from traffic.layout import Layout
from traffic.reservations import INF, Hold

NO_HOLD = 1 << 62  # a route index no route reaches
# s a node stays held after its vehicle leaves it under grid rules (`TrafficManager(
# grid_rules=True)`): more than 0, so a follower always leaves after the vehicle it follows
# (a ring of vehicles each entering the node the next one leaves is never planned: in
# execution each would wait for the next to leave first)
GRID_LEAVE = 0.01


def node_hold_end(depart: float, arrive_next: float, leave: float) -> float:
    """When a node hold ends: on reaching the next node (`leave` < 0: the footprint clears the
    node only then), or under grid rules `leave` s after leaving the node."""
    return arrive_next if leave < 0 else depart + leave


@dataclass(frozen=True)
class Goal:
    """A node to visit and how long to stand there (pick, drop: seconds)."""

    node: str
    dwell: float = 0.0


@dataclass(frozen=True)
class Release:
    """A base extension: route indices up to `base_end` are released, the rest is horizon.

    For VDA 5050: an order update stitching at the previous decision point, nodes 0..base_end
    (sequence ids 2·i) with `released=true`, base_end+1..route_end with `released=false`.
    """

    vehicle_id: str
    plan_id: int
    base_end: int
    route_end: int


@dataclass(frozen=True)
class ReleasePolicy:
    """How far ahead a base may reach: at least the braking distance, at most the base limit.

    A base never reaches more than `max_steps` nodes or `max_distance` metres ahead of the last
    node the vehicle reported (but always at least one node, and at least `braking_distance`
    metres where the plan is free that far).
    """

    max_steps: int = 8
    max_distance: float = 10.0
    braking_distance: float = 1.0


@dataclass(frozen=True)
class Plan:
    """A vehicle's timed route. Indices below `first_index` were kept from the previous plan."""

    vehicle_id: str
    plan_id: int
    nodes: tuple[str, ...]
    arrive: tuple[float, ...]  # planned arrival at each route index (s)
    depart: tuple[float, ...]  # planned departure (inf at the last node)
    stops: tuple[int, ...]  # route index of each goal served
    base_end: int
    complete: bool = True
    first_index: int = 0
    releases: tuple[Release, ...] = field(default=())


class Vehicle:
    """The traffic state of one vehicle: its route, holds and progress (internal)."""

    def __init__(self, name: str, idx: int, cls: int, node: int, heading: int, now: float) -> None:
        self.name, self.idx, self.cls = name, idx, cls
        self.route: list[int] = [node]
        self.arrive: list[float] = [now]
        self.depart: list[float] = [INF]
        self.headings: list[int] = [heading]
        self.metres: list[float] = [0.0]
        self.edge_holds: list[Hold | None] = [None]
        self.node_holds: list[Hold] = []
        self.passed = 0  # last route index the vehicle reported
        self.base = 0  # last released route index (the decision point)
        self.plan_id = 0
        self.first_index = 0
        self.goals: list[tuple[int, float]] = []
        self.stops: list[int] = []  # route index of each goal (huge while not planned)
        self.complete = True
        self.ready_at = now  # it may not leave its node before (handling)
        self.blocked_by = -1  # the vehicle it waits for at its decision point
        self.blocked_since = now
        self.replanned_at = -INF
        self.switch_tried_at = -INF  # last time it tried to go ahead of a late vehicle
        self.static = False
        self.last_progress = now
        self.hold_at = NO_HOLD  # the base stops at this route index (goal_refuge: the last goal)
        self.left = -1  # grid rules: the route index it left (node hold cleared on leaving)

    def restart(self, node: int) -> None:
        """Begin a new route (a new VDA 5050 order) at `node`, where the vehicle stands."""
        park = self.node_holds[-1] if self.node_holds else None
        self.plan_id += 1
        self.route, self.arrive, self.depart = [node], [self.arrive[-1]], [INF]
        self.headings, self.metres, self.edge_holds = [self.headings[-1]], [0.0], [None]
        self.node_holds = [park] if park is not None else []
        if park is not None:
            park.index = 0
        self.passed = self.base = self.first_index = 0
        self.hold_at = NO_HOLD
        self.left = -1

    def truncate(self, last: int) -> None:
        """Keep route indices 0..last (a new horizon follows)."""
        keep = last + 1
        for name in ("route", "arrive", "depart", "headings", "metres", "edge_holds", "node_holds"):
            del getattr(self, name)[keep:]
        self.first_index = last

    def append(
        self,
        node: int,
        arrive: float,
        depart: float,
        heading: int,
        holds: tuple[Hold, Hold],
        length: float,
    ) -> None:
        """Add one step to the route."""
        self.route.append(node)
        self.arrive.append(arrive)
        self.depart.append(depart)
        self.headings.append(heading)
        self.metres.append(self.metres[-1] + length)
        self.edge_holds.append(holds[0])
        self.node_holds.append(holds[1])

    def snapshot(self, layout: Layout, releases: Sequence[Release]) -> Plan:
        """The current plan as handed out."""
        last = len(self.route)
        return Plan(
            vehicle_id=self.name,
            plan_id=self.plan_id,
            nodes=tuple(layout.node_ids[n] for n in self.route),
            arrive=tuple(self.arrive),
            depart=tuple(self.depart),
            stops=tuple(s for s in self.stops if s < last),
            base_end=self.base,
            complete=self.complete,
            first_index=self.first_index,
            releases=tuple(releases),
        )
