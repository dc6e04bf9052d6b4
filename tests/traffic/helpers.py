"""Small layouts and task lists for the traffic planner tests."""

import math
from collections.abc import Iterable, Sequence

from traffic.des import SimConfig, SimStats, Simulation
from traffic.footprint import VehicleClass
from traffic.layout import Layout
from traffic.manager import TrafficManager
from traffic.plans import Goal

AMR = VehicleClass("amr", length=0.8, width=0.5, rotation_speed=math.pi / 2)


class ListTasks:
    """Each vehicle works through its own list of goal lists, then has nothing to do."""

    def __init__(self, tasks: dict[str, list[list[Goal]]]) -> None:
        self.todo = {v: list(t) for v, t in tasks.items()}
        self.done: dict[str, int] = dict.fromkeys(tasks, 0)

    def next_goals(self, vehicle_id: str, node: str, now: float) -> list[Goal] | None:
        todo = self.todo.get(vehicle_id)
        return todo.pop(0) if todo else None

    def finished(self, vehicle_id: str, goals: Sequence[Goal], now: float) -> None:
        self.done[vehicle_id] += 1


def manager(layout: Layout, starts: dict[str, str], **options: object) -> TrafficManager:
    """A manager with vehicles standing (heading east) at `starts`."""
    result = TrafficManager(layout, [AMR], **options)  # type: ignore[arg-type]
    for name, node in starts.items():
        result.add_vehicle(name, node, 0.0, heading=0.0)
    return result


def simulate(
    layout: Layout,
    starts: dict[str, str],
    tasks: dict[str, list[list[Goal]]],
    *,
    until: float = 600.0,
    config: SimConfig | None = None,
) -> tuple[SimStats, ListTasks]:
    """Run the tasks to the end (or `until`) in the discrete-event executor."""
    source = ListTasks(tasks)
    sim = Simulation(manager(layout, starts), source, config or SimConfig(delay_probability=0.0))
    return sim.run(until), source


def cells(rows: Iterable[str]) -> set[tuple[int, int]]:
    """Free cells of a small ASCII map ('.' free, anything else blocked)."""
    return {(r, c) for r, row in enumerate(rows) for c, ch in enumerate(row) if ch != "@"}
