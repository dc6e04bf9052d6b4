"""The live map with 1,000 moving vehicles in headless Chromium: frames and snapshots per second.

Starts the web server (Daphne, `fleet.asgi`) as a process on a throw-away SQLite database and the
Redis channel layer (`--redis-url`, default REDIS_URL), opens the live page in the system
Chromium with Playwright, and drives N vehicles along the aisles of a generated warehouse
through control's real path: VDA 5050 state messages -> `Controller.handle_message` ->
`collect_broadcast` -> compact rows encoded once (`control.service._broadcast_vehicles`) ->
Redis -> `LiveConsumer` -> websocket -> the page, which counts frames drawn and snapshots
applied (`window.fleetMap.stats()`).

Two phases, because on a shared 2-core machine the simulated fleet itself (1,000 state messages
per tick) may not keep up with 5 ticks a second:
1. replay: control's broadcasts of the first ticks are built first (their cost is the server's
   fan-out figure), then sent at exactly `--rate` per second, forth and back, through the same
   channel layer, consumer and websocket; the page figures of the acceptance come from here;
2. live: states fed to the Controller and broadcast as fast as it manages, up to `--rate`.
Target (issue 9): at least 5 frames of updates per second with 1,000 vehicles.
"""

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
import threading
import time
import urllib.request
from pathlib import Path
from typing import Any

from bench.live_map_page import PASSWORD, USER, Page

ROOT = Path(__file__).resolve().parents[1]

SPEED = 1.0  # m/s along the aisles
COLUMNS, ROWS = 40, 25  # the generated warehouse: 40 × 25 aisle nodes, 3 m apart


def prepare(env: dict[str, str]) -> None:
    """Migrate the throw-away database and load the warehouse and a user (in a subprocess, so
    this process can set Django up afterwards on the same file)."""
    subprocess.run(
        [sys.executable, "manage.py", "migrate", "--noinput", "-v", "0"],
        cwd=ROOT,
        env=env,
        check=True,
    )
    script = (
        "from django.contrib.auth import get_user_model\n"
        "from maps.demo import warehouse_layout\n"
        "from maps.services import create_layout\n"
        f"create_layout(spec=warehouse_layout(columns={COLUMNS}, rows={ROWS}, map_id='bench'))\n"
        f"get_user_model().objects.create_superuser('{USER}', 'bench@example.com', '{PASSWORD}')\n"
    )
    subprocess.run(
        [sys.executable, "manage.py", "shell", "-c", script], cwd=ROOT, env=env, check=True
    )


def start_server(env: dict[str, str], port: int) -> subprocess.Popen[bytes]:
    daphne = Path(sys.executable).with_name("daphne")
    server = subprocess.Popen(
        [str(daphne), "-b", "127.0.0.1", "-p", str(port), "fleet.asgi:application"],
        cwd=ROOT,
        env=env,
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
    )
    deadline = time.monotonic() + 60
    while time.monotonic() < deadline:
        try:
            urllib.request.urlopen(f"http://127.0.0.1:{port}/health", timeout=1)
            return server
        except OSError:
            time.sleep(0.3)
    server.terminate()
    raise RuntimeError("the web server did not answer /health within 60 s")


class SimulatedFleet:
    """N vehicles driving back and forth along the aisles, and the Controller they talk to."""

    def __init__(self, vehicles: int) -> None:
        from bench.live_map_store import BenchStore
        from control.controller import Controller

        self.vehicles = vehicles
        self.controller = Controller(store=BenchStore(), interface_name="uagv")
        self.controller.live_page_open = lambda: True  # as with a page open
        self.controller.load()
        self.header = 0

    def tick(self, t: float) -> tuple[list[dict[str, Any]], float, float]:
        """Every vehicle's state at time `t` into the Controller, then its broadcast rows; the
        rows, the ms the states took and the ms collecting the rows took."""
        import vda5050
        from bench.live_map_store import state_message

        began = time.perf_counter()
        self.header += 1
        stamp = vda5050.now_timestamp("2.0.0")
        for i in range(self.vehicles):
            topic, payload = state_message(i, self.header, t, SPEED, COLUMNS, ROWS, stamp)
            self.controller.handle_message(topic, payload)
        if self.header == 1:
            self.controller.flush()  # registers the vehicles (ids for the page)
            for vehicle in self.controller.fleet.vehicles.values():
                vehicle.needs_broadcast = True
        fed = time.perf_counter()
        rows = self.controller.collect_broadcast()
        return rows, (fed - began) * 1e3, (time.perf_counter() - fed) * 1e3


def encode(rows: list[dict[str, Any]], deltas: Any) -> str:
    """The text `control.service._broadcast_vehicles` sends for `rows`: whole rows or changes
    (`deltas`, a control.snapshots.LiveDeltas), encoded once."""
    from fleet.realtime import encode_event

    return encode_event("vehicles.update", deltas.payload(rows))


class Sender(threading.Thread):
    """Sends ready broadcasts at `rate` per second, forth and back, through the channel layer."""

    def __init__(self, texts: list[str], rate: float) -> None:
        super().__init__(daemon=True)
        self.texts = texts
        self.period = 1.0 / rate
        self.stop = threading.Event()
        self.sent = 0

    def run(self) -> None:
        from fleet.realtime import LIVE_GROUP, send_encoded

        next_at = time.monotonic()
        while not self.stop.is_set():
            send_encoded(LIVE_GROUP, self.texts[self.sent % len(self.texts)])
            self.sent += 1
            next_at += self.period
            self.stop.wait(max(0.0, next_at - time.monotonic()))


class Feeder(threading.Thread):
    """The live phase: ticks of the simulated fleet broadcast as run_control does, at most
    `rate` per second."""

    def __init__(self, fleet: SimulatedFleet, rate: float, t0: float) -> None:
        super().__init__(daemon=True)
        self.fleet, self.period, self.t0 = fleet, 1.0 / rate, t0
        self.stop = threading.Event()
        self.sent = 0
        self.error: BaseException | None = None

    def run(self) -> None:
        from control.service import _broadcast_vehicles  # what run_control broadcasts with

        started = time.monotonic()
        try:
            while not self.stop.is_set():
                tick = time.monotonic()
                rows, _, _ = self.fleet.tick(self.t0 + tick - started)
                _broadcast_vehicles(rows)
                self.sent += 1
                self.stop.wait(max(0.0, self.period - (time.monotonic() - tick)))
        except BaseException as error:  # reported by the main thread
            self.error = error


def fan_out_cost(rows: list[dict[str, Any]], repeat: int = 5) -> dict[str, Any]:
    """Server cost of one broadcast of `rows`, once and per browser, now and as it was before
    (every consumer encoding the full rows to JSON; the channel layer packing nested rows).
    Best of `repeat`: the least disturbed by other processes on a shared machine."""
    import msgpack

    def best(work: Any) -> float:
        times = []
        for _ in range(repeat):
            began = time.perf_counter()
            work()
            times.append((time.perf_counter() - began) * 1e3)
        return round(min(times), 2)

    from control.snapshots import LiveDeltas

    text = encode(rows, LiveDeltas())  # a keyframe: whole rows
    message = msgpack.packb({"type": "fleet.json", "text": text}, use_bin_type=True)
    nested = {"type": "fleet.event", "event": "vehicles.update", "payload": {"vehicles": rows}}
    nested_packed = msgpack.packb(nested, use_bin_type=True)
    return {
        "fanout_keyframe_encode_ms": best(lambda: encode(rows, LiveDeltas())),
        "fanout_layer_pack_ms": best(lambda: msgpack.packb({"type": "fleet.json", "text": text})),
        "fanout_per_browser_ms": best(lambda: msgpack.unpackb(message, raw=False)),
        "fanout_keyframe_bytes": len(text.encode()),
        "before_layer_pack_ms": best(lambda: msgpack.packb(nested, use_bin_type=True)),
        "before_per_browser_ms": best(
            lambda: json.dumps(msgpack.unpackb(nested_packed, raw=False)["payload"])
        ),
        "before_bytes": len(json.dumps({"event": "vehicles.update", "payload": nested["payload"]})),
    }


def flat(figures: dict[str, Any]) -> dict[str, Any]:
    """{"server_build_ms": {"p50": 1}} -> {"server_build_ms_p50": 1} (results are flat JSON)."""
    out: dict[str, Any] = {}
    for key, value in figures.items():
        if isinstance(value, dict):
            out.update({f"{key}_{name}": v for name, v in value.items()})
        else:
            out[key] = value
    return out


def summarise(values: list[float]) -> dict[str, float]:
    ordered = sorted(values)
    return {
        "p50": round(statistics.median(ordered), 2),
        "p95": round(ordered[int(0.95 * (len(ordered) - 1))], 2),
        "max": round(ordered[-1], 2),
    }


def run(args: argparse.Namespace, seconds: float, live_seconds: float) -> dict[str, Any]:
    """Build the ticks, open the page, replay at the rate, then run live; all the figures."""
    from playwright.sync_api import sync_playwright

    from control.snapshots import LiveDeltas

    fleet = SimulatedFleet(args.vehicles)
    period = 1.0 / args.rate
    ticks, feed_ms, build_ms, encode_ms = [], [], [], []
    for n in range(args.ticks):
        rows, fed, built = fleet.tick(n * period)
        ticks.append(rows)
        feed_ms.append(fed)
        build_ms.append(built)
    # Encoded in the order they are sent, forth and back (the motion stays continuous), so
    # each change is against what the page was sent before, as in control.
    deltas, texts = LiveDeltas(), []
    for rows in ticks + ticks[-2:0:-1]:
        began = time.perf_counter()
        texts.append(encode(rows, deltas))
        encode_ms.append((time.perf_counter() - began) * 1e3)
    sizes = [len(text.encode()) for text in texts]
    change_sizes = [n for i, n in enumerate(sizes) if i % deltas.keyframe_every]
    figures: dict[str, Any] = {
        "server_feed_states_ms": summarise(feed_ms),
        "server_build_ms": summarise(build_ms),
        "server_encode_once_ms": summarise(encode_ms),
        **fan_out_cost(rows),
        "fanout_changes_bytes": round(statistics.median(change_sizes)),
        "bytes_per_s_per_browser": round(statistics.mean(sizes) * args.rate),
    }
    with sync_playwright() as playwright:
        page = Page(playwright, args.port)
        try:
            sender = Sender(texts, args.rate)
            sender.start()
            try:
                page.wait_for_vehicles(args.vehicles)
                time.sleep(3.0)  # warm up
                figures.update(page.measure(seconds, "page"))
            finally:
                sender.stop.set()
                sender.join(timeout=10)
            if live_seconds:
                feeder = Feeder(fleet, args.rate, t0=args.ticks * period)
                began = time.monotonic()
                feeder.start()
                try:
                    figures.update(page.measure(live_seconds, "live_page"))
                finally:
                    feeder.stop.set()
                    feeder.join(timeout=30)
                figures["live_server_broadcasts_per_s"] = round(
                    feeder.sent / (time.monotonic() - began), 2
                )
                if feeder.error is not None:
                    raise feeder.error
        finally:
            for error in page.errors[:5]:
                print(f"  console error: {error}")
            figures["page_console_errors"] = len(page.errors)
            page.close()
    return figures


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--quick", action="store_true", help="10 s replay + 5 s live")
    parser.add_argument("--vehicles", type=int, default=1000)
    parser.add_argument("--seconds", type=float, default=30.0, help="the replay phase")
    parser.add_argument("--live-seconds", type=float, default=15.0, help="the live phase")
    parser.add_argument("--rate", type=float, default=5.0, help="broadcasts per second")
    parser.add_argument("--ticks", type=int, default=20, help="broadcasts built for the replay")
    parser.add_argument("--port", type=int, default=8765)
    parser.add_argument("--redis-url", default=os.environ.get("REDIS_URL", ""))
    parser.add_argument(
        "--db-file", help="SQLite file to keep between runs (prepared once); default: temporary"
    )
    args = parser.parse_args()
    if not args.redis_url:
        parser.error("a Redis channel layer is needed (--redis-url or REDIS_URL)")
    seconds, live_seconds = (10.0, 5.0) if args.quick else (args.seconds, args.live_seconds)

    workdir = tempfile.TemporaryDirectory(prefix="bench-live-map-")
    db_file = Path(args.db_file).resolve() if args.db_file else Path(workdir.name) / "db.sqlite3"
    env = {
        **os.environ,
        "DJANGO_SETTINGS_MODULE": "bench.live_map_settings",
        "DATABASE_URL": f"sqlite:///{db_file}",
        "REDIS_URL": args.redis_url,
    }
    began = time.monotonic()
    if not db_file.exists():
        prepare(env)
    os.environ.update(env)
    import django

    django.setup()
    print(f"live map: prepared the database in {time.monotonic() - began:.1f} s")
    load_before = round(os.getloadavg()[0], 1)
    server = start_server(env, args.port)
    try:
        measured = run(args, seconds, live_seconds)
    finally:
        server.terminate()
        server.wait(timeout=10)
        workdir.cleanup()
    figures: dict[str, Any] = {
        "vehicles": args.vehicles,
        "rate_per_s": args.rate,
        "seconds": seconds,
        "live_seconds": live_seconds,
        "quick": args.quick,
        "cores": os.cpu_count(),
        "load_average_1min_before": load_before,
        "load_average_1min_after": round(os.getloadavg()[0], 1),
        **measured,
    }
    report(figures)
    from bench import results

    path = results.write("live_map", flat(figures))
    print(f"  written to {path.relative_to(ROOT)}")


def report(f: dict[str, Any]) -> None:
    print(
        f"live map: {f['vehicles']} vehicles, {f['rate_per_s']:g} broadcasts/s "
        f"(load average {f['load_average_1min_before']} before, "
        f"{f['load_average_1min_after']} after, on {f['cores']} cores)"
    )
    for prefix, name in (("page", "replay"), ("live_page", "live")):
        if f"{prefix}_fps_mean" not in f:
            continue
        print(
            f"  {name:6s} page: {f[f'{prefix}_fps_mean']} frames/s (slowest second "
            f"{f[f'{prefix}_fps_min_1s']}), {f[f'{prefix}_snapshots_per_s_mean']} snapshots/s "
            f"applied (slowest second {f[f'{prefix}_snapshots_per_s_min_1s']}), draw "
            f"{f[f'{prefix}_draw_ms_mean']} ms/frame, message "
            f"{f[f'{prefix}_message_ms_mean']} ms, {f[f'{prefix}_bytes_per_s'] / 1e3:,.0f} kB/s, "
            f"CPU per second: main thread {f[f'{prefix}_main_thread_cpu_per_s']} s, renderer "
            f"{f[f'{prefix}_renderer_cpu_per_s']} s"
        )
    if "live_server_broadcasts_per_s" in f:
        print(f"  live: the simulated fleet + control sent {f['live_server_broadcasts_per_s']}/s")
    print(f"  console errors: {f['page_console_errors']}")
    for name in ("feed_states", "build", "encode_once"):
        s = f[f"server_{name}_ms"]
        print(f"  server {name:12s} p50 {s['p50']:7.1f} ms  p95 {s['p95']:7.1f} ms")
    print(
        f"  fan-out of {f['vehicles']} vehicles (best of 5): keyframe encoded once "
        f"{f['fanout_keyframe_encode_ms']} ms, layer pack {f['fanout_layer_pack_ms']} ms, per "
        f"browser {f['fanout_per_browser_ms']} ms (before: pack {f['before_layer_pack_ms']} ms, "
        f"per browser {f['before_per_browser_ms']} ms)"
    )
    print(
        f"  bytes per broadcast: keyframe {f['fanout_keyframe_bytes'] / 1e3:,.0f} kB, changes "
        f"{f['fanout_changes_bytes'] / 1e3:,.0f} kB (before: every broadcast "
        f"{f['before_bytes'] / 1e3:,.0f} kB); {f['bytes_per_s_per_browser'] / 1e3:,.0f} kB/s "
        f"per browser"
    )


if __name__ == "__main__":
    main()
