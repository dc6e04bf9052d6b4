"""`python -m bench.traffic.release_tail STATE | --s2 INSTANCE [--delays] [--seconds S]
[--repeat N]`: the release decision's own cost per state message, told apart from the
machine's interruptions.

A run saved by `bench.traffic --state` (S1, S3) is driven on `seconds` simulated seconds, or an
S2 instance (whose runs are not saved) from its start, `repeat` times,
each in a process of its own (two at a time, the cores here). The simulation is deterministic,
so every repeat makes the same `on_progress` calls in the same order (checked); a call's
smallest CPU time over the repeats is its cost with the machine's interruptions mostly gone (a
call slow in every repeat is slow itself, one slow in a single repeat was interrupted). Prints
the tail of a single repeat (what a run reports) and of the per-call minimum.
"""

from __future__ import annotations

import argparse
import multiprocessing
import time
from array import array
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from bench.results import write
from bench.traffic import scenarios
from bench.traffic.fleet import percentile
from bench.traffic.long_run import load
from traffic.des import Simulation
from traffic.plans import Release

LIMIT = 1e-3  # s: the target per state message (issue 6)


Call = tuple[str, int, float]  # an on_progress call: vehicle, route index reached, time


@dataclass
class Repeat:
    """One repeat's on_progress calls in call order, and the CPU seconds of each."""

    calls: list[Call]
    cpu: array[float]


@dataclass(frozen=True)
class S2Start:
    """An S2 instance from its start, in the benchmark's lifelong mode (seed 1)."""

    instance: str
    delays: bool = False


Source = Path | S2Start  # a saved run, or an S2 instance


def start(source: Source) -> tuple[Simulation, float]:
    """The simulation to drive and the simulated time it stands at."""
    if isinstance(source, S2Start):
        instance, manager, config = scenarios.s2_setup(
            source.instance, seed=1, delays=source.delays
        )
        return Simulation(manager, scenarios.LorrTasks(instance), config), 0.0
    saved = load(source)
    if saved.simulation is None:
        raise ValueError(f"{source} holds a run that has not begun")
    return saved.simulation, saved.after


def drive(source: Source, seconds: float) -> Repeat:
    """Drive `source` on `seconds`, timing every state message's decision."""
    simulation, after = start(source)
    manager = simulation.manager
    decide = manager.on_progress
    timed = Repeat([], array("d"))

    def decide_timed(vehicle_id: str, passed: int, now: float) -> list[Release]:
        began = time.process_time()
        releases = decide(vehicle_id, passed, now)
        timed.cpu.append(time.process_time() - began)
        timed.calls.append((vehicle_id, passed, now))
        return releases

    manager.on_progress = decide_timed  # type: ignore[method-assign]
    simulation.run(until=after + seconds)
    return timed


def tail(cpu: Sequence[float]) -> dict[str, float]:
    """p50, p99, p99.9, p99.99, maximum (µs) and the count over `LIMIT` of `cpu`."""
    ordered = sorted(cpu)

    def pct(q: float) -> float:
        return round(percentile(ordered, q) * 1e6, 1)  # (sorting sorted values is linear)

    return {
        "p50_us": pct(50),
        "p99_us": pct(99),
        "p99_9_us": pct(99.9),
        "p99_99_us": pct(99.99),
        "max_us": round(ordered[-1] * 1e6, 1),
        "over_1ms": sum(s > LIMIT for s in ordered),
    }


def measure(source: Source, seconds: float, repeat: int) -> dict[str, Any]:
    """Drive `source` on `repeat` times and compare the repeats call by call."""
    with multiprocessing.get_context("fork").Pool(min(2, repeat)) as pool:
        repeats = pool.starmap(drive, [(source, seconds)] * repeat)
    calls = repeats[0].calls
    if any(r.calls != calls for r in repeats):
        raise RuntimeError("the repeats made different calls: the run is not deterministic")
    least = [min(each) for each in zip(*(r.cpu for r in repeats), strict=True)]
    singles = [tail(r.cpu) for r in repeats]
    slowest = sorted(range(len(least)), key=least.__getitem__, reverse=True)[:5]
    return {
        "source": str(source),
        "seconds": seconds,
        "repeats": repeat,
        "state_messages": len(least),
        "single_repeat_worst": max(singles, key=lambda t: (t["over_1ms"], t["max_us"])),
        "single_repeats_over_1ms": [t["over_1ms"] for t in singles],
        "per_call_minimum": tail(least),
        "slowest_calls": [  # by their least CPU time, with each repeat's
            {
                "vehicle": calls[i][0],
                "index": calls[i][1],
                "at_s": round(calls[i][2], 3),
                "cpu_us": [round(r.cpu[i] * 1e6, 1) for r in repeats],
            }
            for i in slowest
        ],
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("state", type=Path, nargs="?", help="a run saved by bench.traffic --state")
    parser.add_argument("--s2", metavar="INSTANCE", help="instead: an S2 instance from its start")
    parser.add_argument("--delays", action="store_true", help="--s2: 5 %% of moves delayed")
    parser.add_argument("--seconds", type=float, default=300.0, help="simulated seconds")
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--tag", default="", help="results file suffix")
    parser.add_argument("--no-write", action="store_true", help="print only")
    args = parser.parse_args()
    if args.repeat < 2:
        parser.error("--repeat: at least 2, to compare")
    if (args.state is None) == (args.s2 is None):
        parser.error("give a saved run or --s2 INSTANCE")
    source = args.state or S2Start(args.s2, args.delays)
    figures = measure(source, args.seconds, args.repeat)
    for key, value in figures.items():
        print(f"  {key:26} {value}")
    if not args.no_write:
        suffix = f"_{args.tag}" if args.tag else ""
        print(f"  -> {write(f'traffic_release_tail{suffix}', figures)}")


if __name__ == "__main__":
    main()
