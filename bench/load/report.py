"""The figures of one load-benchmark run, from two samples taken around the window."""

import argparse
import math
import os
import platform
from typing import Any

PUMP_TICK_HZ = 10.0  # bench.load.run starts the pumps with --tick-hz 10
# control counters reported as their growth in the window
TRAFFIC_COUNTERS = (
    *("traffic_searches_repeated", "traffic_searches_moved"),
    *("traffic_replans", "traffic_replans_unchanged", "traffic_problems", "traffic_no_plan"),
)


def _on_ticks(interval: float, tick_hz: float = PUMP_TICK_HZ) -> float:
    """The periodic state interval as the pumps keep it: a state falls due on the first tick
    at least `interval` after the last one."""
    return math.ceil(round(interval * tick_hz, 6)) / tick_hz


def _delta_histogram_p(
    before: dict[str, Any], after: dict[str, Any], q: float
) -> float | str | None:
    """Upper bucket bound (ms) under which fraction `q` of the window's observations fall
    (a string "> N" when they fall beyond the last bound)."""
    if not before or not after:
        return None
    counts = [a - b for a, b in zip(after["counts"], before["counts"], strict=True)]
    total = sum(counts)
    if not total:
        return None
    running = 0
    for bound, count in zip([*after["bounds"], float("inf")], counts, strict=True):
        running += count
        if running >= q * total:
            if bound == float("inf"):
                return f"> {after['bounds'][-1] * 1e3:g}"
            return round(float(bound) * 1e3, 2)
    return None


def _difference(before: int | None, after: int | None) -> int | None:
    return None if before is None or after is None else after - before


def _count_delta(before: dict[str, Any], after: dict[str, Any], key: str) -> int | None:
    """Observations of histogram `key` in the window (None: not in the snapshots)."""
    if key not in before or key not in after:
        return None
    return int(sum(after[key]["counts"]) - sum(before[key]["counts"]))


def report(
    args: argparse.Namespace,
    before: dict[str, Any],
    after: dict[str, Any],
    probes: dict[str, Any],
    memory: dict[str, float],
    registered_s: float,
    info: dict[str, Any],
) -> dict[str, Any]:
    wall = after["wall"] - before["wall"]
    cpu = {n: round((after["cpu"][n] - before["cpu"][n]) / wall, 4) for n in after["cpu"]}
    kernel = {  # of that, in the kernel (sockets, select, page faults)
        n: round((after["cpu_kernel"][n] - before["cpu_kernel"][n]) / wall, 4)
        for n in after.get("cpu_kernel", {})
        if n in before.get("cpu_kernel", {})
    }
    db = {
        k: after["db"][k] - before["db"][k] for k in ("inserted", "updated", "deleted", "commits")
    }
    c0, c1 = before["control"], after["control"]
    control: dict[str, Any] = {}
    if c0 and c1:
        span = c1["time"] - c0["time"]
        topics = {
            k: round((v - c0["messages_by_topic"].get(k, 0)) / span, 1)
            for k, v in c1["messages_by_topic"].items()
        }
        handled = c1["counters"].get("messages", 0) - c0["counters"].get("messages", 0)
        control = {
            "messages_per_s": round(handled / span, 1),
            "by_topic_per_s": topics,
            "decode_errors": c1["counters"].get("decode_errors", 0),
            "handler_errors": c1["counters"].get("handler_errors", 0),
            **{
                name: c1["counters"].get(name, 0) - c0["counters"].get(name, 0)
                for name in TRAFFIC_COUNTERS
            },
            "handling_p50_ms": _delta_histogram_p(
                c0["handling_seconds"], c1["handling_seconds"], 0.5
            ),
            "handling_p99_ms": _delta_histogram_p(
                c0["handling_seconds"], c1["handling_seconds"], 0.99
            ),
            "state_to_order_p50_ms_bucket": _delta_histogram_p(
                c0["state_to_order_seconds"], c1["state_to_order_seconds"], 0.5
            ),
            "state_to_order_p99_ms_bucket": _delta_histogram_p(
                c0["state_to_order_seconds"], c1["state_to_order_seconds"], 0.99
            ),
            # RELIABILITY.md §5 "Load": ingest lag (a state's age when control applied it;
            # vehicles and control share this machine's clock) and header-id gaps (messages
            # lost between vehicle and control)
            **{
                f"ingest_lag_{label}_ms_bucket": _delta_histogram_p(
                    c0.get("state_age_seconds", {}), c1.get("state_age_seconds", {}), q
                )
                for label, q in (("p50", 0.5), ("p99", 0.99), ("max", 1.0))
            },
            "header_gaps": c1.get("vehicle_counters", {}).get("gaps", 0)
            - c0.get("vehicle_counters", {}).get("gaps", 0),
            "vehicles_executing": c1.get("vehicles_executing"),
            # at the end of the window: wait-for cycles and stalled vehicles (both must be 0)
            "traffic_safety": c1.get("traffic_safety", {}),
            # What stalls the paho thread: the GIL held elsewhere (or no free core), collections.
            **{
                f"{name}_{label}_ms_bucket": _delta_histogram_p(
                    c0.get(f"{name}_seconds", {}), c1.get(f"{name}_seconds", {}), q
                )
                for name in ("wakeup_delay", "gc_young_pause", "gc_full_pause")
                for label, q in (("p50", 0.5), ("p99", 0.99), ("max", 1.0))
            },
            "gc_young_collections": _count_delta(c0, c1, "gc_young_pause_seconds"),
            "gc_full_collections": _count_delta(c0, c1, "gc_full_pause_seconds"),
        }
    raw = probes["raw"]
    raw_rate = raw.get("messages_per_s") or 0
    state_rate = raw.get("by_topic_per_s", {}).get("state", 0)
    ratio = round(control["messages_per_s"] / raw_rate, 3) if control and raw_rate else None
    cpu_ratio = round(cpu["control"] / raw["cpu_share"], 2) if raw.get("cpu_share") else None
    # By cause when control logged causes (probes._causal), else the heuristic pairing.
    latency_p99 = raw.get("state_to_update_causal_p99_ms", raw.get("state_to_update_p99_ms"))
    api_p95 = probes["api"].get("post_to_published_p95_ms")
    return {
        "config": {
            "vehicles": args.vehicles,
            "pumps": args.pumps,
            "seconds": args.seconds,
            "warmup": args.warmup,
            "state_interval": args.state_interval,
            "visualization_hz": args.visualization_hz,
            "order_rate": args.order_rate,
            "workload": args.workload,
            "park_after_s": args.park_after,
            "traffic": args.traffic,
            "max_queued_messages": args.max_queued,
            "time_scale": args.time_scale,
            "layout_nodes": info["nodes"],
            "layout_stations": info["stations"],
            "cores": os.cpu_count(),
            "python": platform.python_version(),
        },
        "registered_s": round(registered_s, 1),
        "load_average": {"start": before["load"], "end": after["load"]},
        "cpu_share": cpu,
        "cpu_share_kernel": kernel,
        "control_cpu_vs_raw_subscriber": cpu_ratio,
        "memory_rss_mb": memory,
        "raw_subscriber": raw,
        "control": control,
        "receive_ratio_control_to_raw": ratio,
        "api": probes["api"],
        "browser": probes["ws"],
        "db_rows_per_s": {k: round(v / wall, 1) for k, v in db.items()},
        # RELIABILITY.md §5 "Load": messages Mosquitto dropped in the window ($SYS)
        "broker_dropped": _difference(before.get("broker_dropped"), after.get("broker_dropped")),
        "offered_per_s": {  # what the vehicles would send if the pumps got the CPU they need
            "state": round(args.vehicles / _on_ticks(args.state_interval), 1),
            "visualization": round(args.vehicles * args.visualization_hz, 1),
        },
        "targets": {
            "state_messages_per_s": state_rate,
            "control_cpu_le_25pct": cpu["control"] <= 0.25,
            "state_to_update_p99_le_50ms": latency_p99 is not None and latency_p99 <= 50,
            "api_to_published_p95_le_500ms": api_p95 is not None and api_p95 <= 500,
        },
    }
