"""Grid maps for the traffic benchmark: a MovingAI-style warehouse generator and the LoRR files.

`warehouse()` regenerates the pattern of MovingAI `warehouse-10-20-10-2-1` (161×63 cells: a
border wall, 10 × 20 shelf blocks of 10×2 cells with 1-cell aisles between them, 25-cell open
margins left and right) instead of storing it (MovingAI maps carry no open licence). Workstations
sit in the margins on a lattice (odd row, odd column) so a vehicle standing at one never blocks
a lane; pick locations are the aisle cells next to a shelf.
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path

LORR = Path(__file__).resolve().parents[3] / "shared" / "bench" / "lorr2023"


@dataclass(frozen=True)
class GridMap:
    """Free cells of a grid map, with the cells tasks use."""

    height: int
    width: int
    free: frozenset[tuple[int, int]]
    picks: tuple[tuple[int, int], ...] = ()
    stations: tuple[tuple[int, int], ...] = ()

    def cell(self, index: int) -> tuple[int, int]:
        """LoRR cell index (row * width + col) as (row, col)."""
        return divmod(index, self.width)


def warehouse(
    *,
    block_cols: int = 10,
    block_rows: int = 20,
    block_len: int = 10,
    block_h: int = 2,
    aisle: int = 1,
    margin: int = 25,
    station_cols: int = 2,
) -> GridMap:
    """A MovingAI-pattern warehouse (defaults: warehouse-10-20-10-2-1, 161×63, 5,699 free).

    `station_cols` lattice columns of workstations per margin, next to the outer walls.
    """
    height = 2 + aisle + block_rows * (block_h + aisle)
    width = 2 + 2 * margin + block_cols * (block_len + aisle) - aisle
    shelves: set[tuple[int, int]] = set()
    for br in range(block_rows):
        top = 1 + aisle + br * (block_h + aisle)
        for bc in range(block_cols):
            left = 1 + margin + bc * (block_len + aisle)
            for r in range(top, top + block_h):
                for c in range(left, left + block_len):
                    shelves.add((r, c))
    free = frozenset(
        (r, c) for r in range(1, height - 1) for c in range(1, width - 1) if (r, c) not in shelves
    )
    picks = tuple(
        sorted(
            (r, c)
            for r, c in free
            if any((r + dr, c + dc) in shelves for dr, dc in ((0, 1), (1, 0), (0, -1), (-1, 0)))
        )
    )
    columns = [1 + 2 * k for k in range(station_cols)]
    columns += [width - 2 - 2 * k for k in range(station_cols)]
    stations = tuple(
        sorted((r, c) for r in range(1, height - 1, 2) for c in columns if (r, c) in free)
    )
    return GridMap(height, width, free, picks, stations)


def movingai(path: Path) -> GridMap:
    """A MovingAI / LoRR `.map` file (`.`, `E`, `S`, `G` free; `E` stations, `S` picks)."""
    lines = path.read_text().splitlines()
    height = int(lines[1].split()[1])
    width = int(lines[2].split()[1])
    rows = lines[4 : 4 + height]
    free, picks, stations = set(), [], []
    for r, row in enumerate(rows):
        for c, ch in enumerate(row):
            if ch in ".GES":
                free.add((r, c))
                if ch == "S":
                    picks.append((r, c))
                elif ch == "E":
                    stations.append((r, c))
    return GridMap(height, width, frozenset(free), tuple(picks), tuple(stations))


@dataclass(frozen=True)
class LorrInstance:
    """A LoRR 2023 problem: map, agent start cells, errand cells, steps, best-known score."""

    name: str
    grid: GridMap
    starts: tuple[int, ...]
    tasks: tuple[int, ...]
    steps: int
    best_known: int

    def errand(self, agent: int, k: int) -> int:
        """The k-th errand of `agent` under the 2023 `roundrobin` rule."""
        return self.tasks[(k * len(self.starts) + agent) % len(self.tasks)]


BEST_KNOWN = {
    "MR23-I-04": 1741,
    "MR23-I-03": 3042,
    "MR23-I-05": 7432,
    "MR23-I-07": 5914,
    "MR23-I-08": 6059,
}


def lorr(name: str) -> LorrInstance:
    """Load a `random.domain` main-round instance from shared/bench/lorr2023."""
    problem_path = LORR / "random.domain" / f"{name}.json"
    problem = json.loads(problem_path.read_text())
    base = problem_path.parent
    grid = movingai(base / problem["mapFile"])
    team = int(problem["teamSize"])
    agents = _numbers(base / problem["agentFile"])[:team]
    tasks = _numbers(base / problem["taskFile"])
    steps = int(json.loads((LORR / "simulation_time.json").read_text())[name.removeprefix("MR23-")])
    return LorrInstance(name, grid, tuple(agents), tuple(tasks), steps, BEST_KNOWN[name])


def _numbers(path: Path) -> list[int]:
    lines = [ln for ln in path.read_text().splitlines() if ln.strip() and not ln.startswith("#")]
    return [int(ln.split(",")[0]) for ln in lines[1:]]
