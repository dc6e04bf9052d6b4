"""A long warehouse run that can be saved at its checkpoints and resumed in another process
(`bench.traffic --state FILE`, `--resume FILE`), and the figures kept of each checkpoint."""

from __future__ import annotations

import gzip
import os
import pickle  # noqa: S403 (a saved run is the benchmark's own file)
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from bench.traffic.fleet import Run, Tour, WarehouseTasks, figures, ghost_at, run
from traffic.des import SimConfig, Simulation
from traffic.manager import TrafficManager


@dataclass
class LongRun:
    """A warehouse run with its ghost's tours, which can be saved at each checkpoint and
    resumed from there in another process (`bench.traffic --state FILE`, `--resume FILE`):
    an 8 h S3 run takes longer than one session here. The resumed run is the same run."""

    manager: TrafficManager
    tasks: WarehouseTasks
    config: SimConfig
    seconds: float
    seed: int
    settings: dict[str, Any]
    tours: list[list[Tour]]
    cuts: list[float]
    setup: float
    checkpoints: list[dict[str, Any]] = field(default_factory=list)
    simulation: Simulation | None = None  # saved at the cut `after` (None: not begun)
    after: float = 0.0
    wall: float = 0.0  # wall seconds until then, over every process that ran it

    def go(
        self,
        on_checkpoint: Callable[[dict[str, Any]], object] | None = None,
        state: Path | None = None,
    ) -> dict[str, Any]:
        """Run (on) to the end; at each cut the figures go to `on_checkpoint` and the whole
        run to `state`."""

        def cut(so_far: Run) -> None:
            measured = figures(so_far, seed=self.seed)
            self.checkpoints.append(_with_ghost(measured, so_far, self.tours))
            if state is not None:
                self.simulation, self.after = so_far.simulation, so_far.seconds
                self.wall = so_far.wall
                save(self, state)
            if on_checkpoint is not None:
                trail = _trail(self.checkpoints)
                partial = {**self.checkpoints[-1], **self.settings, "partial": True}
                on_checkpoint({**partial, "checkpoints": trail})

        result = run(
            self.manager,
            self.tasks,
            self.seconds,
            self.config,
            cuts=self.cuts,
            on_cut=cut,
            resume=self.simulation,
            after=self.after,
            wall_before=self.wall,
        )
        out = _with_ghost(figures(result, seed=self.seed), result, self.tours)
        if self.checkpoints:
            out["checkpoints"] = _trail(self.checkpoints)
        out.update(self.settings, setup_s=round(self.setup, 2))
        return out


def save(long_run: LongRun, path: Path) -> None:
    """Write `long_run` to `path` (replaced whole: a process stopped while writing leaves the
    previous cut's file)."""
    partial = path.with_name(path.name + ".part")
    with gzip.open(partial, "wb", compresslevel=1) as f:
        pickle.dump(long_run, f, protocol=pickle.HIGHEST_PROTOCOL)
    os.replace(partial, path)


def resume(
    path: Path,
    on_checkpoint: Callable[[dict[str, Any]], object] | None = None,
    state: Path | None = None,
) -> dict[str, Any]:
    """Go on with a run saved by `save` (the file is the project's own output, trusted)."""
    with gzip.open(path, "rb") as f:
        long_run = pickle.load(f)  # noqa: S301 (our own file)
    if not isinstance(long_run, LongRun):
        raise TypeError(f"{path} holds no saved traffic run")
    return long_run.go(on_checkpoint, state)


# what the results keep of each checkpoint of a long run (the whole figures go to
# `on_checkpoint`)
CHECKPOINT_KEYS = (
    "simulated_hours",
    "tasks_finished",
    "ghost_tasks_finished",
    "rho",
    "rho_work",
    "collisions",
    "deadlocks_wait_cycles",
    "deadlocks_stalls",
    "moves",
    "wall_s",
)


def _trail(checkpoints: list[dict[str, Any]]) -> list[dict[str, Any]]:
    """What the results keep of each checkpoint so far."""
    return [{k: c[k] for k in CHECKPOINT_KEYS} for c in checkpoints]


def _with_ghost(out: dict[str, Any], result: Run, tours: list[list[Tour]]) -> dict[str, Any]:
    """`out` plus the ghost's figures at the run's end and the ratios to them."""
    ghosted, ghost_work = ghost_at(tours, result.seconds)
    hours = result.seconds / 3600
    out["ghost_tasks_finished"] = ghosted
    out["ghost_throughput_per_hour"] = round(ghosted / hours, 1)
    out["rho"] = round(len(result.stats.tasks) / ghosted, 3) if ghosted else 0.0
    # the same ratio with the open tasks' progress counted: S3's tours take 15 to 30 minutes,
    # so over half an hour the count depends on where the cut falls in each tour
    out["work_tasks"] = round(result.work, 1)
    out["ghost_work_tasks"] = round(ghost_work, 1)
    out["rho_work"] = round(result.work / ghost_work, 3) if ghost_work else 0.0
    return out
