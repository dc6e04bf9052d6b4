"""The safety net of a discrete-event run: collisions, wait-for cycles, and stalls with their
wait-for chains.

`Occupancy` tracks what each vehicle physically occupies, independently of the manager's
bookkeeping, and counts a collision whenever a vehicle starts to occupy resources that
conflict with another vehicle's.

A vehicle that has not moved for `stall_after` seconds while work is left is a **stall** only if
the vehicle at the end of its wait-for chain has not moved for that long either; a long wait
behind a vehicle that is driving is counted apart (`SimStats.long_waits`). Each stall is logged
with its chain, one line per vehicle: its node, route indices, whether it moves, how long it
stood, its goals and the holds queued ahead of its next step (why it does not move).
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Protocol

from traffic.des_records import SimStats
from traffic.footprint import ConflictSets
from traffic.manager import TrafficManager
from traffic.plans import Goal


class Occupancy:
    """The resources each vehicle physically occupies (its node; while it drives the segment
    and the next node), and the collisions when one starts to occupy another's."""

    def __init__(self, conflicts: ConflictSets) -> None:
        self.conflicts = conflicts
        self._occupant: dict[int, set[int]] = {}

    def move(self, car: int, cls: int, before: tuple[int, ...], now: tuple[int, ...]) -> int:
        """Vehicle `car` (class `cls`) leaves `before` for `now`: the collisions this makes."""
        occupant = self._occupant
        for r in before:
            occupant[r].discard(car)
        collisions = 0
        for r in now:
            for other in self.conflicts.of(cls, r):
                collisions += sum(1 for w in occupant.get(other, ()) if w != car)
        for r in now:
            occupant.setdefault(r, set()).add(car)
        return collisions


class WatchedCar(Protocol):
    """What the watch reads of a simulated vehicle (`traffic.des`)."""

    name: str
    moving: bool
    goals: list[Goal] | None
    last_move: float  # when it last reached a node (or got a task)
    stalled: bool  # counted already, until it moves again


class StallWatch:
    """Counts wait-for cycles and stalls into a run's `SimStats`."""

    def __init__(
        self,
        manager: TrafficManager,
        cars: Sequence[WatchedCar],
        stats: SimStats,
        stall_after: float,
    ) -> None:
        self.manager, self.stats, self.stall_after = manager, stats, stall_after
        self._cars = cars
        self._by_name = {c.name: c for c in cars}

    def check(self, now: float) -> None:
        """Count the wait-for cycles, and every vehicle that became a stall or a long wait."""
        self.stats.wait_cycles += len(self.manager.wait_cycles())
        limit = self.stall_after
        for car in self._cars:
            v = self.manager.vehicle(car.name)
            busy = car.goals is not None or v.passed < len(v.route) - 1
            if not busy or car.moving or car.stalled or now - car.last_move <= limit:
                continue
            car.stalled = True
            root = self._root(car)
            if root.moving or now - root.last_move <= limit:
                self.stats.long_waits += 1
            else:
                self.stats.stalls += 1
                self.stats.stall_chains.append(self.describe_chain(car, now))

    def describe_chain(self, car: WatchedCar, now: float) -> str:
        """The stalled vehicle's wait-for chain, one line per vehicle (why it does not move)."""
        manager = self.manager
        lines, seen = [f"t={now:.0f}"], set()
        while car.name not in seen:
            seen.add(car.name)
            v = manager.vehicle(car.name)
            step = v.base + 1
            holds = (v.edge_holds[step], v.node_holds[step]) if step < len(v.route) else ()
            ahead = [repr(o) for h in holds if h for o in manager.table.blockers(h)]
            lines.append(
                f"{car.name} at {manager.layout.node_ids[v.route[v.passed]]} "
                f"passed {v.passed} base {v.base} route {len(v.route)} moving {car.moving} "
                f"still {now - car.last_move:.0f}s ready_at {v.ready_at:.0f} "
                f"goals {car.goals is not None} complete {v.complete} static {v.static} "
                f"blocked_by {v.blocked_by} ahead {ahead}"
            )
            following = manager.waiting_for(car.name)
            if not following:
                break
            car = self._by_name[following[0]]
        return " | ".join(lines)

    def _root(self, car: WatchedCar) -> WatchedCar:
        """The end of the chain of vehicles `car` waits for."""
        seen = {car.name}
        while True:
            ahead = self.manager.waiting_for(car.name)
            if not ahead or ahead[0] in seen:
                return car
            car = self._by_name[ahead[0]]
            seen.add(car.name)
