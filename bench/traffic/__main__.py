"""`python -m bench.traffic [--quick] [--scenario S1|S2|S3] [--hours H] [--instances ...]`."""

import argparse
from collections.abc import Callable
from dataclasses import replace
from functools import partial
from pathlib import Path
from typing import Any

from bench.results import write
from bench.traffic import long_run, scenarios


def main() -> None:
    parser = argparse.ArgumentParser(description="Traffic manager benchmark (issue 6)")
    parser.add_argument("--quick", action="store_true", help="a run of about a minute")
    parser.add_argument("--scenario", choices=["S1", "S2", "S3"], action="append")
    parser.add_argument(
        "--hours", type=float, help="simulated hours (S2: instead of the instance's steps)"
    )
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument("--instances", nargs="*", default=(), help="S2: LoRR instance names")
    parser.add_argument("--no-write", action="store_true", help="print only")
    parser.add_argument("--tag", default="", help="results file suffix (a shorter run)")
    parser.add_argument(
        "--quick-search",
        help="S1/S3: EXPANSIONS,WEIGHT of the bounded first search, or 'off' (default: "
        "1000,2 for S1, 1000,1.3 for S3)",
    )
    parser.add_argument(
        "--lifelong",
        choices=["on", "off"],
        help="goal refuges and stepping aside (traffic.aside); default: on for S2, off otherwise",
    )
    parser.add_argument(
        "--retime-slack",
        type=float,
        default=2.0,
        help="S1/S3: seconds a plan may run early before tick() re-times it",
    )
    parser.add_argument(
        "--retime-growth",
        type=float,
        default=0.0,
        help="S1/S3: a vehicle s seconds without progress is re-timed GROWTH*s past its "
        "earliest departure (fewer pushes of long waits; 0: off)",
    )
    parser.add_argument(
        "--tick-every",
        type=float,
        default=1.0,
        help="S1/S3: simulated seconds between the manager's ticks (re-timing, re-plans of "
        "waiting vehicles; releases do not wait for them)",
    )
    parser.add_argument(
        "--switch-push",
        default="",
        help="SECONDS: a vehicle waiting behind a late one may go ahead of it, pushing the late "
        "one's plan back at most this long (traffic.switching), or 'off'; default: "
        f"{scenarios.SWITCH_PUSH:g} for S3 and lifelong S2, off for S1",
    )
    parser.add_argument(
        "--congestion",
        default="",
        help="AGAINST,THROUGH seconds per planned step of the others' routes the other way "
        "along a move's edge and into its end node (traffic.congestion), or 'off'; default: "
        f"{','.join(f'{x:g}' for x in scenarios.S2_CONGESTION)} for lifelong S2, off otherwise",
    )
    parser.add_argument(
        "--grid-rules",
        choices=["on", "off"],
        help="S2: LoRR's cells, a vehicle may follow into a cell being left (TrafficManager("
        f"grid_rules=True)); default: {'on' if scenarios.S2_GRID_RULES else 'off'}",
    )
    parser.add_argument(
        "--delays",
        choices=["on", "off"],
        default="off",
        help="S2: 5 %% of moves delayed 5-30 s as in S1/S3 (LoRR's rules have none)",
    )
    parser.add_argument(
        "--checkpoint-hours",
        type=float,
        help="S1/S3: write the figures so far every H simulated hours (a long run that is cut "
        "short leaves them; the file says partial)",
    )
    parser.add_argument(
        "--cuts-here",
        action="store_true",
        help="S1/S3 with --checkpoint-hours: measure and save each cut in this process "
        "(default: in a forked one, on the other core, while this one drives on)",
    )
    parser.add_argument(
        "--base",
        type=int,
        help="S3: nodes (and metres) a base may reach ahead (default: "
        f"{scenarios.S3_POLICY.max_steps}; S1 keeps {scenarios.POLICY.max_steps})",
    )
    parser.add_argument(
        "--state",
        type=Path,
        help="S1/S3 with --checkpoint-hours: save the whole run to FILE at every checkpoint "
        "(gzip'd pickle), to be resumed with --resume",
    )
    parser.add_argument(
        "--resume",
        type=Path,
        help="go on with a run saved by --state (its scenario and settings; --tag, "
        "--no-write and --state as given now)",
    )
    args = parser.parse_args()
    if args.state and not (args.checkpoint_hours or args.resume):
        parser.error("--state saves at checkpoints: give --checkpoint-hours too")
    if args.resume:
        _resume(args.resume, args.tag, args.no_write, args.state, aside=not args.cuts_here)
        return
    chosen = args.scenario or ["S1", "S2", "S3"]
    for name in chosen:
        figures: dict[str, Any]
        lifelong = args.lifelong == "on" if args.lifelong else name == "S2"
        switch_push = _switch_push(args.switch_push, name, lifelong)
        if name == "S2":
            figures = scenarios.s2(
                quick=args.quick,
                seed=args.seed,
                instances=args.instances,
                lifelong=lifelong,
                switch_push=switch_push,
                congestion=_congestion(args.congestion, name, lifelong),
                grid_rules=(args.grid_rules or ("on" if scenarios.S2_GRID_RULES else "off"))
                == "on",
                hours=args.hours,
                delays=args.delays == "on",
            )
        else:
            extra: dict[str, Any] = {}
            if name == "S3" and args.base:
                extra["base"] = replace(
                    scenarios.S3_POLICY, max_steps=args.base, max_distance=float(args.base)
                )
            runner = scenarios.s1 if name == "S1" else scenarios.s3
            bound: tuple[int, float] | None = (
                scenarios.QUICK_SEARCH if name == "S1" else scenarios.S3_QUICK_SEARCH
            )
            if args.quick_search == "off":
                bound = None
            elif args.quick_search:
                cap, weight = args.quick_search.split(",")
                bound = (int(cap), float(weight))
            figures = runner(
                quick=args.quick,
                seed=args.seed,
                hours=args.hours,
                quick_search=bound,
                lifelong=lifelong,
                retime_slack=args.retime_slack,
                retime_growth=args.retime_growth,
                tick_every=args.tick_every,
                switch_push=switch_push,
                congestion=_congestion(args.congestion, name, lifelong),
                checkpoint_hours=args.checkpoint_hours,
                on_checkpoint=None if args.no_write else _writer(name, args.tag),
                state=args.state,
                aside=not args.cuts_here,
                **extra,
            )
        figures["quick"] = args.quick
        _report(name, figures, args.tag, args.no_write)


def _resume(path: Path, tag: str, no_write: bool, state: Path | None, *, aside: bool) -> None:
    """Go on with a saved run and report it as the run itself would have."""

    def checkpoint(figures: dict[str, Any]) -> object:
        return None if no_write else _writer(figures["scenario"], tag)(figures)

    figures = long_run.resume(path, checkpoint, state, aside=aside)
    figures["quick"] = False
    figures["resumed_from"] = str(path)
    _report(figures["scenario"], figures, tag, no_write)


def _report(name: str, figures: dict[str, Any], tag: str, no_write: bool) -> None:
    """Print a scenario's figures and write them (unless `no_write`)."""
    print(f"== {name}")
    for key, value in figures.items():
        print(f"  {key:32} {value}")
    if not no_write:
        print(f"  -> {_writer(name, tag)(figures)}")


def _writer(scenario: str, tag: str) -> Callable[[dict[str, Any]], Path]:
    """Writes a scenario's figures to bench/results/traffic_<scenario>[_<tag>].json."""
    suffix = f"_{tag}" if tag else ""
    return partial(write, f"traffic_{scenario.lower()}{suffix}")


def _congestion(given: str, scenario: str, lifelong: bool) -> tuple[float, float] | None:
    """The flow cost (against, through) of a run (None: off)."""
    if given == "off":
        return None
    if given:
        against, through = given.split(",")
        return float(against), float(through)
    return scenarios.S2_CONGESTION if scenario == "S2" and lifelong else None


def _switch_push(given: str, scenario: str, lifelong: bool) -> float | None:
    """The switching push limit of a run (None: no switching)."""
    if given == "off":
        return None
    if given:
        return float(given)
    on = scenario == "S3" or (scenario == "S2" and lifelong)
    return scenarios.SWITCH_PUSH if on else None


if __name__ == "__main__":
    main()
