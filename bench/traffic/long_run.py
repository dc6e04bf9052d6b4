"""A long warehouse run that can be saved at its checkpoints and resumed in another process
(`bench.traffic --state FILE`, `--resume FILE`), and the figures kept of each checkpoint."""

from __future__ import annotations

import gzip
import lzma
import os
import pickle  # noqa: S403 (a saved run is the benchmark's own file)
import traceback
from collections.abc import Callable
from dataclasses import dataclass, field
from functools import partial
from pathlib import Path
from typing import Any, BinaryIO, cast

from bench.traffic.fleet import Run, Tour, WarehouseTasks, figures, ghost_at, run
from traffic.des import SimConfig, Simulation
from traffic.footprint import VehicleClass
from traffic.layout import Layout
from traffic.manager import TrafficManager
from traffic.sipp import ClassGraph


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
        *,
        aside: bool = False,
    ) -> dict[str, Any]:
        """Run (on) to the end; at each cut the figures go to `on_checkpoint` and the whole
        run to `state`. With `aside` a forked process measures and saves each cut while this
        one drives on: on S3 a cut's figures take minutes of free-flow searches and its save
        a minute, a fifth of the run on one core (the figures are the same either way)."""
        pending: _Child | None = None

        def keep(so_far: Run) -> dict[str, Any]:
            measured = _with_ghost(figures(so_far, seed=self.seed), so_far, self.tours)
            self.checkpoints.append(measured)
            if state is not None:
                self.simulation, self.after = so_far.simulation, so_far.seconds
                self.wall = so_far.wall
                save(self, state)
            if on_checkpoint is not None:
                trail = _trail(self.checkpoints)
                partial = {**self.checkpoints[-1], **self.settings, "partial": True}
                on_checkpoint({**partial, "checkpoints": trail})
            return measured

        def collect() -> None:
            nonlocal pending
            if pending is not None:
                self.checkpoints.append(pending.wait())
                pending = None

        def cut(so_far: Run) -> None:
            nonlocal pending
            collect()  # the previous cut's child is long done: cuts are simulated hours apart
            if aside:
                pending = _Child.start(partial(keep, so_far))
            else:
                keep(so_far)

        try:
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
        finally:
            collect()
        out = _with_ghost(figures(result, seed=self.seed), result, self.tours)
        if self.checkpoints:
            out["checkpoints"] = _trail(self.checkpoints)
        out.update(self.settings, setup_s=round(self.setup, 2))
        return out


class _Child:
    """A forked process that works out one value (a cut's figures) and pipes it back."""

    def __init__(self, pid: int, pipe: int) -> None:
        self.pid, self.pipe = pid, pipe

    @classmethod
    def start(cls, work: Callable[[], object]) -> _Child:
        """Fork; the child runs `work`, sends its result and exits."""
        read, write = os.pipe()
        pid = os.fork()
        if pid == 0:  # the child: never returns into the run
            os.close(read)
            code = 1
            try:
                with os.fdopen(write, "wb") as out:
                    pickle.dump(work(), out)
                code = 0
            except BaseException:  # noqa: BLE001 (reported, then the child exits)
                traceback.print_exc()
            finally:
                os._exit(code)
        os.close(write)
        return cls(pid, read)

    def wait(self) -> Any:
        """The child's result (it is read before waiting: a large one fills the pipe)."""
        with os.fdopen(self.pipe, "rb") as pipe:
            data = pipe.read()
        _, status = os.waitpid(self.pid, 0)
        if os.waitstatus_to_exitcode(status) != 0 or not data:
            raise RuntimeError("a cut measured aside failed (its traceback is printed above)")
        return pickle.loads(data)  # noqa: S301 (our own child's)


def save(long_run: LongRun, path: Path) -> None:
    """Write `long_run` to `path` (replaced whole: a process stopped while writing leaves the
    previous cut's file).

    The vehicle classes' graphs (`ClassGraph`, over half of an S3 file) are left out and
    rebuilt from the layout on `resume`: a file small enough to keep between sessions.
    """
    partial = path.with_name(path.name + ".part")
    graphs = long_run.manager.graphs
    with _writer(partial, xz=path.suffix == ".xz") as f:
        saver = _Saver(f)
        # one pickler, one memo: the layout written with the header is the run's own
        saver.dump(_Header(long_run.manager.layout, [(g.vehicle, g._cache) for g in graphs]))
        saver.graphs = {id(g): i for i, g in enumerate(graphs)}
        saver.dump(long_run)
    os.replace(partial, path)


def resume(
    path: Path,
    on_checkpoint: Callable[[dict[str, Any]], object] | None = None,
    state: Path | None = None,
    *,
    aside: bool = False,
) -> dict[str, Any]:
    """Go on with a run saved by `save` (the file is the project's own output, trusted)."""
    return load(path).go(on_checkpoint, state, aside=aside)


def load(path: Path) -> LongRun:
    """The run saved in `path`, its graphs rebuilt (a file of the nineteenth round, pickled
    whole with them, loads as well)."""
    with _reader(path) as f:
        loader = _Loader(f)
        first = loader.load()
        if isinstance(first, _Header):
            loader.graphs = [ClassGraph(first.layout, v, cache=c) for v, c in first.graphs]
            first = loader.load()
    if not isinstance(first, LongRun):
        raise TypeError(f"{path} holds no saved traffic run")
    return first


def _writer(path: Path, *, xz: bool) -> BinaryIO:
    """gzip (fast: every cut of a run) or xz (half the size: a file kept in the repository
    between sessions)."""
    if xz:
        return cast(BinaryIO, lzma.open(path, "wb", preset=6))
    return cast(BinaryIO, gzip.open(path, "wb", compresslevel=1))


def _reader(path: Path) -> BinaryIO:
    """The file decompressed, gzip or xz by its first bytes."""
    with path.open("rb") as f:
        magic = f.read(6)
    if magic == b"\xfd7zXZ\x00":
        return cast(BinaryIO, lzma.open(path, "rb"))
    return cast(BinaryIO, gzip.open(path, "rb"))


@dataclass
class _Header:
    """What a saved run's graphs are rebuilt from: the layout, each class with its cache size."""

    layout: Layout
    graphs: list[tuple[VehicleClass, int]]


class _Saver(pickle.Pickler):
    """Pickles each graph in `graphs` (by id, set after the header) as its index."""

    def __init__(self, file: BinaryIO) -> None:
        super().__init__(file, protocol=pickle.HIGHEST_PROTOCOL)
        self.graphs: dict[int, int] = {}

    def persistent_id(self, obj: object) -> int | None:
        return self.graphs.get(id(obj))


class _Loader(pickle.Unpickler):
    """Reads a graph index back as the graph rebuilt from the header (set after reading it)."""

    def __init__(self, file: BinaryIO) -> None:
        super().__init__(file)
        self.graphs: list[ClassGraph] = []

    def persistent_load(self, pid: object) -> ClassGraph:
        if not isinstance(pid, int) or not 0 <= pid < len(self.graphs):
            raise pickle.UnpicklingError(f"no graph {pid!r} in this saved run")
        return self.graphs[pid]


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


def main() -> None:
    """`python -m bench.traffic.long_run SRC DST`: write the run saved in SRC to DST (xz if
    DST ends in .xz; a whole file of the nineteenth round comes out without its graphs)."""
    import argparse

    parser = argparse.ArgumentParser(description=main.__doc__)
    parser.add_argument("source", type=Path)
    parser.add_argument("target", type=Path)
    args = parser.parse_args()
    # run as __main__ this module is a second copy: the saved run's classes are the package's
    from bench.traffic import long_run

    long_run.save(long_run.load(args.source), args.target)
    print(f"{args.target}: {args.target.stat().st_size / 1e6:.1f} MB")


if __name__ == "__main__":
    main()
