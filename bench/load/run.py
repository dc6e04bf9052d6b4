"""Load benchmark: 1,000 simulated vehicles against the real processes of the fleet.

Started here, each as its own process: a Mosquitto of our own (free port, `max_connections
-1`, file limit raised), `control` (`manage.py run_control`), a Celery worker and beat, the web
app under daphne, one or two `simulator.pump` processes with the vehicles (state every
`--state-interval` s and visualization at `--visualization-hz`, driving the orders they get),
and the probes of `bench.load.probes`: a bare paho subscriber on control's topics (the floor
for control's receive rate and CPU), an ERP client posting transport orders at a steady rate
and a live-page websocket. Everything uses its own PostgreSQL database (dropped and created)
and its own Redis database. After the vehicles are registered and a warm-up, the run measures
for `--seconds`: CPU and memory of every process (psutil), database rows written per second
(pg_stat_database deltas), control's own counters (its metrics snapshot in Redis), the
probes' figures, and the load average. Figures go to stdout and bench/results/load.json.

    nice -n 5 python -m bench.load [--vehicles 1000] [--seconds 120] [--quick]
"""

import argparse
import json
import os
import re
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

import psycopg
import redis

from bench import results
from bench.load.probes import WORKLOADS
from bench.load.processes import (
    ROOT,
    BrokerDrops,
    Child,
    create_database,
    db_stats,
    free_ports,
    order_stages,
    order_statuses,
    python,
    wait_for,
)
from bench.load.report import PUMP_TICK_HZ, report

SNAPSHOT_KEY = "fleet:control:metrics"  # control.metrics.SNAPSHOT_KEY (bench stays Django-free)
MOSQUITTO_CONF = """\
listener {port} 127.0.0.1
allow_anonymous true
# 1,000+ vehicles: no connection cap (the file limit is the real one, raised below).
max_connections -1
max_queued_messages {max_queued}
max_inflight_messages 20
set_tcp_nodelay true
persistence false
# $SYS/broker/publish/messages/dropped every second: the run reports the drops in its window
sys_interval 1
log_dest stderr
log_type error
log_type warning
# notices name the client whose queue overflowed ("Outgoing messages are being dropped for
# client X"): the run reports them next to the $SYS count
log_type notice
"""


def split_layout(layout_file: Path, pumps: int, vehicles: int) -> list[tuple[Path, int, str]]:
    """One layout file per pump (its vehicles start on their own park spurs) and the
    vehicles.json the API client uses (serial number and home park station per vehicle)."""
    layout = json.loads(layout_file.read_text())
    stations = {s["node"]: s["id"] for s in layout["stations"]}
    parking = layout["parking"][:vehicles]
    per_pump = -(-vehicles // pumps)
    plan, fleet = [], []
    for p in range(pumps):
        mine = parking[p * per_pump : (p + 1) * per_pump]
        path = layout_file.with_name(f"layout-{p + 1}.json")
        path.write_text(json.dumps({**layout, "parking": mine}))
        prefix = f"P{p + 1}-"
        plan.append((path, len(mine), prefix))
        fleet += [(f"{prefix}{i + 1}", stations[node]) for i, node in enumerate(mine)]
    (layout_file.parent / "vehicles.json").write_text(json.dumps(fleet))
    return plan


def run(args: argparse.Namespace) -> dict[str, Any]:
    work = Path(tempfile.mkdtemp(prefix="loadbench-"))
    print(f"logs in {work}", flush=True)
    port, web_port, health_port = free_ports(3)
    (work / "mosquitto.conf").write_text(
        MOSQUITTO_CONF.format(port=port, max_queued=args.max_queued)
    )
    admin_url = f"{args.postgres}/postgres"
    db_url = f"{args.postgres}/{args.database}"
    create_database(admin_url, args.database)
    # A fresh start (a left-over snapshot or queued tasks of an earlier run would count).
    redis.Redis.from_url(args.redis).delete(
        SNAPSHOT_KEY, "celery", "fleet:control:commands", "fleet:dispatch:requested"
    )
    interface = f"load{os.getpid()}"
    env = {k: v for k, v in os.environ.items() if not k.startswith("PYTEST")}
    env.update(
        DJANGO_SETTINGS_MODULE="fleet.settings",
        DATABASE_URL=db_url,
        REDIS_URL=args.redis,
        MQTT_URL=f"mqtt://127.0.0.1:{port}",
        VDA5050_INTERFACE=interface,
        CELERY_TASK_ALWAYS_EAGER="0",
        FLEET_TRAFFIC="1" if args.traffic else "0",
        # vehicles left on a drop station go to park after 10 s idle (orders go to any vehicle)
        FLEET_TRAFFIC_PARK_AFTER=str(args.park_after),
        ALLOWED_HOSTS="127.0.0.1,localhost",
        LOG_LEVEL="WARNING",
        API_CLIENT_RATE="100000/min",
        CONTROL_HEALTH_PORT=str(health_port),
        CONTROL_CAUSE_LOG=str(work / "causes.jsonl"),  # the causal latency (probes._causal)
    )
    subprocess.run(python("manage.py", "migrate", "-v", "0"), cwd=ROOT, env=env, check=True)
    setup = subprocess.run(
        python(
            "-m",
            "bench.load.setup",
            *("--vehicles", str(args.vehicles), "--out", str(work)),
            *(["--shelves"] if args.workload == "zone" else []),
        ),
        cwd=ROOT,
        env=env,
        check=True,
        capture_output=True,
        text=True,
    )
    info = json.loads(setup.stdout.strip().splitlines()[-1])
    plan = split_layout(work / "layout.json", args.pumps, args.vehicles)
    url = f"http://127.0.0.1:{web_port}"
    children = [Child("mosquitto", ["mosquitto", "-c", str(work / "mosquitto.conf")], env, work)]
    time.sleep(0.5)
    children += [
        Child("control", python("manage.py", "run_control"), env, work),
        Child(
            "worker",
            python("-m", "celery", "-A", "fleet", "worker", "--concurrency", "2", "-l", "WARNING"),
            env,
            work,
        ),
        Child(
            "beat",
            python(
                "-m", "celery", "-A", "fleet", "beat", "-l", "WARNING", "-s", str(work / "beat")
            ),
            env,
            work,
        ),
        Child(
            "web",
            python(
                "-m", "daphne", "-b", "127.0.0.1", "-p", str(web_port), "fleet.asgi:application"
            ),
            env,
            work,
        ),
    ]
    time.sleep(3.0)  # control subscribed before the vehicles announce themselves
    for number, (layout, count, prefix) in enumerate(plan, start=1):
        argv = ["-m", "simulator.pump", "--count", str(count), "--layout", str(layout)]
        argv += ["--broker", f"mqtt://127.0.0.1:{port}", "--interface", interface]
        argv += ["--serial-prefix", prefix, "--state-interval", str(args.state_interval)]
        argv += ["--visualization-hz", str(args.visualization_hz), "--speed", str(args.speed)]
        argv += [
            "--time-scale",
            str(args.time_scale),
            "--tick-hz",
            str(PUMP_TICK_HZ),
            "--log-level",
            "WARNING",
        ]
        children.append(Child(f"pump{number}", python(*argv), env, work))
    try:
        return measure(args, work, children, info, url, port, interface, db_url)
    finally:
        codes = {child.name: child.stop(timeout=60.0) for child in reversed(children)}
        print(f"exit codes: {codes}")
        if not args.keep:
            shutil.rmtree(work, ignore_errors=True)
            with psycopg.connect(admin_url, autocommit=True) as connection:
                connection.execute(f'DROP DATABASE IF EXISTS "{args.database}" WITH (FORCE)')


def measure(
    args: argparse.Namespace,
    work: Path,
    children: list[Child],
    info: dict[str, Any],
    url: str,
    port: int,
    interface: str,
    db_url: str,
) -> dict[str, Any]:
    started = time.monotonic()
    wait_for(
        # 99 %: on a starved machine a few vehicles flap UNREACHABLE (state timeout) for a while
        lambda: db_stats(db_url, args.database)["online"] >= 0.99 * args.vehicles,
        args.register_timeout,
        f"{args.vehicles} vehicles registered online",
        children,
    )
    registered_s = time.monotonic() - started
    print(f"vehicles online after {registered_s:.1f} s; warming up", flush=True)
    start = time.time() + args.warmup
    common = ["--broker", f"127.0.0.1:{port}", "--interface", interface]
    common += ["--start", str(start), "--seconds", str(args.seconds)]
    probes = [
        Child(
            "raw",
            python(
                "-m",
                "bench.load.probes",
                "raw",
                *common,
                "--out",
                str(work / "raw.json"),
                "--causes",
                str(work / "causes.jsonl"),
            ),
            os.environ.copy(),
            work,
        ),
        Child(
            "api",
            python(
                "-m",
                "bench.load.probes",
                "api",
                *common,
                "--out",
                str(work / "api.json"),
                "--url",
                url,
                "--token",
                info["token"],
                "--layout",
                str(work / "layout.json"),
                "--fleet",
                str(work / "vehicles.json"),
                "--rate",
                str(args.order_rate),
                "--workload",
                args.workload,
            ),
            os.environ.copy(),
            work,
        ),
        Child(
            "ws",
            python(
                "-m",
                "bench.load.probes",
                "ws",
                *common,
                "--out",
                str(work / "ws.json"),
                "--url",
                url,
                "--session",
                info["session"],
            ),
            os.environ.copy(),
            work,
        ),
    ]
    rds = redis.Redis.from_url(args.redis)
    drops = BrokerDrops(port)  # subscribed until the window ends (its docstring says why)
    time.sleep(max(0.0, start - time.time()))
    before = sample(children, rds, db_url, args.database, drops)
    if args.py_spy:  # where control's CPU goes, as collapsed stacks (flamegraph input)
        control = next(c for c in children if c.name == "control")
        argv = ["py-spy", "record", "-p", str(control.popen.pid), "-d", str(int(args.seconds))]
        argv += ["-f", "raw", "-o", str(work / "control.stacks"), "--nonblocking", "--gil"]
        probes.append(
            Child(
                "py-spy",
                [str(Path(sys.executable).parent / argv[0]), *argv[1:]],
                os.environ.copy(),
                work,
            )
        )
    time.sleep(args.seconds)
    after = sample(children, rds, db_url, args.database, drops)
    drops.close()
    for probe in probes:
        probe.popen.wait(timeout=args.seconds + 120)  # all end on their own
        probe.log.close()
    probe_results = {}
    for name in ("raw", "api", "ws"):
        path = work / f"{name}.json"
        probe_results[name] = json.loads(path.read_text()) if path.exists() else {"missing": True}
    timeline = probe_results["api"].pop("timeline", None)
    if timeline:
        probe_results["api"]["stages"] = order_stages(db_url, timeline)
        probe_results["api"]["status_at_end"] = order_statuses(db_url, timeline)
    memory = {child.name: child.rss_mb() for child in children}
    figures = report(args, before, after, probe_results, memory, registered_s, info)
    figures["broker_dropping_clients"] = dropping_clients(work / "mosquitto.log")
    return figures


def dropping_clients(log: Path) -> list[str]:
    """The clients Mosquitto dropped outgoing messages for (it logs each when it starts)."""
    if not log.exists():
        return []
    found = re.findall(
        r"Outgoing messages are being dropped for client (\S+?)\.?$", log.read_text(), re.M
    )
    return sorted(set(found))


def sample(
    children: list[Child], rds: redis.Redis, db_url: str, database: str, drops: BrokerDrops
) -> dict[str, Any]:
    raw = rds.get(SNAPSHOT_KEY)
    return {
        "broker_dropped": drops.read(),
        "wall": time.monotonic(),
        "cpu": {child.name: child.cpu_seconds() for child in children},
        "cpu_kernel": {child.name: child.cpu_seconds(kernel_only=True) for child in children},
        "db": db_stats(db_url, database),
        "control": json.loads(raw) if raw else {},
        "load": os.getloadavg(),
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    add = parser.add_argument
    add("--vehicles", type=int, default=1000)
    add("--pumps", type=int, default=2, help="simulator processes")
    add("--seconds", type=float, default=120.0, help="measurement window")
    add("--warmup", type=float, default=20.0)
    # 0.45: a state falls due on the first 10 Hz tick 0.45 s after the last, i.e. every 0.5 s,
    # 2,000 a second from 1,000 vehicles (0.5 gave 0.5–0.6 s: about 1,760–1,850 a second)
    add("--state-interval", type=float, default=0.45, help="s between periodic states")
    add("--visualization-hz", type=float, default=1.0)
    add("--order-rate", type=float, default=1.0, help="transport orders posted per second")
    add(
        "--workload",
        choices=tuple(WORKLOADS),
        default="zone",
        help="; ".join(f"{name}: {text}" for name, text in WORKLOADS.items()),
    )
    add("--speed", type=float, default=1.0)
    add("--time-scale", type=float, default=4.0, help="simulated time runs this much faster")
    add("--no-traffic", dest="traffic", action="store_false")
    add("--park-after", type=float, default=10.0, help="idle s before a vehicle parks; 0: off")
    # ~10 s of 1,000 vehicles at 2 messages/s: control rides out a stall without losing any
    add("--max-queued", type=int, default=20000, help="Mosquitto max_queued_messages")
    add("--postgres", default="postgres://postgres@127.0.0.1:5432")
    add("--database", default="fleet_loadbench_run")
    add("--redis", default="redis://127.0.0.1:6379/6")
    add("--register-timeout", type=float, default=240.0)
    add("--keep", action="store_true", help="keep the logs directory")
    add("--py-spy", action="store_true", help="profile control in the window (with --keep)")
    add("--quick", action="store_true", help="50 vehicles, one pump, 15 s")
    add("--out", default="load", help="name of the JSON file under bench/results")
    add("--json", type=Path, help="write the figures to this file instead (tests)")
    args = parser.parse_args()
    if args.quick:
        args.vehicles, args.pumps, args.seconds, args.warmup = 50, 1, 15.0, 5.0
    result = run(args)
    print(json.dumps(result, indent=2))
    if args.json:
        args.json.write_text(json.dumps(result, indent=2))
    else:
        print(f"written to {results.write(args.out, result)}")
