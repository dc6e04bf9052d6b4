"""A long warehouse run leaves its figures on the way (`--checkpoint-hours`): cutting the run
changes nothing in it, each cut is measured against the ghost at the same time, and a run
saved at a cut (`--state`) and resumed (`--resume`) is the same run. The tick interval
(`--tick-every`) reaches the simulation."""

import gzip
import pickle
import subprocess
import sys
from pathlib import Path
from typing import Any

import pytest

from bench.traffic import long_run, scenarios
from bench.traffic.fleet import Run, ghost, ghost_at, ghost_tours, run
from bench.traffic.maps import warehouse
from tests.traffic.helpers import ListTasks, cells, manager
from traffic.des import SimConfig
from traffic.layout import Layout
from traffic.plans import Goal

LANE = Layout.grid(cells(["..........."]))  # 0,0 .. 0,10: ten 1 m moves east
SMALL = warehouse(block_cols=2, block_rows=2, margin=3, station_cols=1)


def _shuttle(trips: int, vehicle: str = "a") -> ListTasks:
    return ListTasks({vehicle: [[Goal("0,10")], [Goal("0,0")]] * trips})


def test_a_run_cut_into_pieces_is_the_same_run() -> None:
    config = SimConfig(seed=3, delay_probability=0.3)
    whole = run(manager(LANE, {"a": "0,0"}), _shuttle(5), 90.0, config)
    seen: list[Run] = []
    m = manager(LANE, {"a": "0,0"})
    pieces = run(m, _shuttle(5), 90.0, config, cuts=[60.0, 30.0], on_cut=seen.append)
    assert [r.seconds for r in seen] == [30.0, 60.0]
    assert [t.done for t in pieces.stats.tasks] == [t.done for t in whole.stats.tasks]
    assert pieces.stats.moves == whole.stats.moves > 0
    assert pieces.work == whole.work
    # the figures at a cut are those of a run that stops there
    at_30 = run(manager(LANE, {"a": "0,0"}), _shuttle(5), 30.0, config)
    assert seen[0].work == at_30.work


def test_the_ghost_at_a_cut_counts_as_a_ghost_run_to_that_cut() -> None:
    m = manager(LANE, {"a": "0,0"})
    config = SimConfig(seed=3, delay_probability=0.3)
    start = [("0,0", 0.0)]
    tours = ghost_tours(m, start, _shuttle(20, "v0"), 200.0, config)
    for cut in (25.0, 80.0, 200.0):
        assert ghost_at(tours, cut) == ghost(m, start, _shuttle(20, "v0"), cut, config)
    assert 0 < ghost_at(tours, 25.0)[1] < ghost_at(tours, 80.0)[1]


def test_a_warehouse_run_reports_every_checkpoint() -> None:
    written: list[dict[str, Any]] = []
    out = scenarios.warehouse_scenario(
        "S1", SMALL, 4, 0.06, seed=1, max_expansions=5_000, checkpoint_hours=0.02,
        on_checkpoint=written.append,
    )  # fmt: skip
    assert [w["simulated_hours"] for w in written] == [0.02, 0.04]
    assert all(w["partial"] and w["vehicles"] == 4 and w["map"] == out["map"] for w in written)
    assert [len(w["checkpoints"]) for w in written] == [1, 2]
    trail = out["checkpoints"]
    assert [c["simulated_hours"] for c in trail] == [0.02, 0.04]
    finished = [c["tasks_finished"] for c in trail] + [out["tasks_finished"]]
    assert finished == sorted(finished)
    assert finished[-1] > 0
    assert "partial" not in out
    assert out["ghost_tasks_finished"] >= trail[-1]["ghost_tasks_finished"] > 0


def test_the_tick_interval_reaches_the_simulation() -> None:
    every_second = scenarios.warehouse_scenario("S1", SMALL, 4, 0.02, seed=1, max_expansions=5_000)
    every_two = scenarios.warehouse_scenario(
        "S1", SMALL, 4, 0.02, seed=1, max_expansions=5_000, tick_every=2.0
    )
    assert every_second["ticks"] == 72  # 0.02 h
    assert every_two["ticks"] == 36
    assert every_two["tick_every"] == 2.0


def test_a_run_saved_at_a_checkpoint_and_resumed_is_the_same_run(tmp_path: Path) -> None:
    settings: dict[str, Any] = dict(max_expansions=5_000, checkpoint_hours=0.02, switch_push=10.0)
    whole = scenarios.warehouse_scenario("S1", SMALL, 4, 0.06, seed=1, **settings)
    state = tmp_path / "run.pkl.gz"
    saved: list[float] = []

    def stop_after_first(figures: dict[str, Any]) -> None:
        saved.append(figures["simulated_hours"])
        raise _Stopped  # the session ends right after the first cut was written

    with pytest.raises(_Stopped):
        scenarios.warehouse_scenario(
            "S1", SMALL, 4, 0.06, seed=1, state=state, on_checkpoint=stop_after_first, **settings
        )
    assert saved == [0.02]
    assert state.exists()
    written: list[dict[str, Any]] = []
    resumed = long_run.resume(state, written.append, state)
    assert [w["simulated_hours"] for w in written] == [0.04]  # only the cuts after the save
    same = ("tasks_finished", "moves", "delayed_moves", "rho", "rho_work", "switches")
    assert {k: resumed[k] for k in same} == {k: whole[k] for k in same}
    assert resumed["moves"] > 0
    assert [c["moves"] for c in resumed["checkpoints"]] == [
        c["moves"] for c in whole["checkpoints"]
    ]
    assert resumed["wall_s"] >= resumed["checkpoints"][0]["wall_s"]


def test_a_saved_run_leaves_its_graphs_out_and_a_run_pickled_whole_still_resumes(
    tmp_path: Path,
) -> None:
    state = _saved_at_first_cut(tmp_path)
    saved = long_run.load(state)
    graph = saved.manager.graphs[0]
    assert graph.layout is saved.manager.layout  # rebuilt from the saved layout
    assert saved.simulation is not None
    assert saved.simulation.manager is saved.manager
    whole = tmp_path / "whole.pkl.gz"  # as the nineteenth round wrote it: graphs and all
    with gzip.open(whole, "wb") as f:
        pickle.dump(saved, f, protocol=pickle.HIGHEST_PROTOCOL)
    assert b"ClassGraph" in gzip.decompress(whole.read_bytes())
    assert b"ClassGraph" not in gzip.decompress(state.read_bytes())
    assert state.stat().st_size < whole.stat().st_size
    kept = tmp_path / "run.pkl.xz"  # the smaller file kept between sessions
    long_run.save(saved, kept)
    assert kept.read_bytes()[:6] == b"\xfd7zXZ\x00"
    same = ("tasks_finished", "moves", "delayed_moves", "rho_work")
    from_state, from_whole = long_run.resume(state), long_run.resume(whole)
    assert {k: from_state[k] for k in same} == {k: from_whole[k] for k in same}
    assert {k: long_run.resume(kept)[k] for k in same} == {k: from_state[k] for k in same}
    assert from_state["moves"] > saved.checkpoints[-1]["moves"]


def test_cuts_measured_aside_give_the_same_figures_and_state(tmp_path: Path) -> None:
    settings: dict[str, Any] = dict(max_expansions=5_000, checkpoint_hours=0.02)
    here = scenarios.warehouse_scenario("S1", SMALL, 4, 0.06, seed=1, **settings)
    state = tmp_path / "run.pkl.gz"
    written: list[dict[str, Any]] = []  # in the child: nothing comes back this way
    aside = scenarios.warehouse_scenario(
        "S1", SMALL, 4, 0.06, seed=1, state=state, on_checkpoint=written.append, aside=True,
        **settings,
    )  # fmt: skip
    assert written == []
    keys = [k for k in long_run.CHECKPOINT_KEYS if k != "wall_s"]
    assert [[c[k] for k in keys] for c in aside["checkpoints"]] == [
        [c[k] for k in keys] for c in here["checkpoints"]
    ]
    assert len(aside["checkpoints"]) == 2
    assert aside["tasks_finished"] == here["tasks_finished"]
    saved = long_run.load(state)  # written by the second cut's child
    assert saved.after == 0.04 * 3600
    assert [c["moves"] for c in saved.checkpoints] == [c["moves"] for c in here["checkpoints"]]


def test_a_cut_that_fails_aside_stops_the_run() -> None:
    def broken(figures: dict[str, Any]) -> None:
        raise OSError("disk full")

    with pytest.raises(RuntimeError, match="measured aside failed"):
        scenarios.warehouse_scenario(
            "S1", SMALL, 4, 0.04, seed=1, max_expansions=5_000, checkpoint_hours=0.02,
            on_checkpoint=broken, aside=True,
        )  # fmt: skip


def test_the_command_line_re_saves_a_run_as_xz(tmp_path: Path) -> None:
    state = _saved_at_first_cut(tmp_path)
    kept = tmp_path / "kept.pkl.xz"
    done = subprocess.run(  # noqa: S603 (our own module)
        [sys.executable, "-m", "bench.traffic.long_run", str(state), str(kept)],
        cwd=Path(__file__).resolve().parents[2],
        capture_output=True,
        text=True,
        check=False,
    )
    assert done.returncode == 0, done.stderr
    assert "kept.pkl.xz" in done.stdout
    assert long_run.load(kept).after == long_run.load(state).after == 0.02 * 3600


def test_resume_refuses_a_file_that_holds_no_run(tmp_path: Path) -> None:
    other = tmp_path / "other.pkl.gz"
    with gzip.open(other, "wb") as f:
        pickle.dump({"not": "a run"}, f)
    with pytest.raises(TypeError, match="no saved traffic run"):
        long_run.resume(other)


class _Stopped(Exception):
    pass


def _saved_at_first_cut(tmp_path: Path) -> Path:
    """A small S1 run (0.04 h) whose session ended right after its first cut (0.02 h) was saved."""
    state = tmp_path / "run.pkl.gz"

    def stop(figures: dict[str, Any]) -> None:
        raise _Stopped

    with pytest.raises(_Stopped):
        scenarios.warehouse_scenario(
            "S1", SMALL, 4, 0.04, seed=2, max_expansions=5_000, checkpoint_hours=0.02,
            state=state, on_checkpoint=stop,
        )  # fmt: skip
    return state
