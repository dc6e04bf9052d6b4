"""Throw-away Mosquitto, Redis and PostgreSQL instances for one fault row.

Each row runs its own services on free ports in a temporary directory, so killing and restarting
them never touches the shared services. Every signal goes to a process id we started (the
broker's and Redis' `Popen`, the postmaster's pid from its `postmaster.pid`).
"""

import contextlib
import fcntl
import hashlib
import os
import shutil
import signal
import socket
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
PG_BIN = Path("/usr/lib/postgresql/15/bin")
TEMPLATE_ROOT = Path(tempfile.gettempdir()) / "fleet-faults-templates"


def free_port() -> int:
    with socket.socket() as sock:
        sock.bind(("127.0.0.1", 0))
        return int(sock.getsockname()[1])


def port_open(port: int) -> bool:
    with socket.socket() as sock:
        sock.settimeout(0.2)
        return sock.connect_ex(("127.0.0.1", port)) == 0


def wait_port(port: int, timeout: float = 20.0, up: bool = True) -> float:
    """Seconds until the port accepts (or, `up=False`, refuses) connections."""
    started = time.monotonic()
    while time.monotonic() - started < timeout:
        if port_open(port) == up:
            return time.monotonic() - started
        time.sleep(0.05)
    raise TimeoutError(f"port {port} not {'up' if up else 'down'} after {timeout:.0f} s")


def _as_user(user: str) -> list[str]:
    """Run as `user` when we are root (PostgreSQL refuses root; Mosquitto drops to its user)."""
    return ["runuser", "-u", user, "--"] if os.geteuid() == 0 else []


def _chown(path: Path, user: str) -> None:
    if os.geteuid() == 0:
        shutil.chown(path, user, user)


class Mosquitto:
    """A broker with persistence saved on every change (RELIABILITY §0.2: SIGKILL keeps QoS 1)."""

    def __init__(self, workdir: Path) -> None:
        self.dir = workdir / "mosquitto"
        self.dir.mkdir(parents=True, exist_ok=True)
        _chown(self.dir, "mosquitto")
        self.port = free_port()
        self.conf = self.dir / "mosquitto.conf"
        self.conf.write_text(
            f"listener {self.port} 127.0.0.1\nallow_anonymous true\n"
            f"persistence true\npersistence_location {self.dir}/\n"
            "autosave_on_changes true\nautosave_interval 1\n"
            "max_queued_messages 100000\n"
            f"log_dest file {self.dir}/mosquitto.log\n"
        )
        self.popen: subprocess.Popen[bytes] | None = None

    @property
    def url(self) -> str:
        return f"mqtt://127.0.0.1:{self.port}"

    def start(self) -> float:
        self.popen = subprocess.Popen(
            ["mosquitto", "-c", str(self.conf)],
            stdout=subprocess.DEVNULL,
            stderr=subprocess.DEVNULL,
            preexec_fn=_raise_nofile,
        )
        return wait_port(self.port)

    def signal(self, sig: int) -> None:
        assert self.popen is not None
        self.popen.send_signal(sig)
        self.popen.wait(timeout=30)
        wait_port(self.port, up=False)

    def stop(self) -> None:
        if self.popen is not None and self.popen.poll() is None:
            self.signal(signal.SIGTERM)


def _raise_nofile() -> None:
    import resource

    soft, hard = resource.getrlimit(resource.RLIMIT_NOFILE)
    resource.setrlimit(resource.RLIMIT_NOFILE, (min(4096, hard), hard))


class Redis:
    """redis-server with AOF (everysec) in its own directory."""

    def __init__(self, workdir: Path, *, appendonly: bool = True) -> None:
        self.dir = workdir / "redis"
        self.dir.mkdir(parents=True, exist_ok=True)
        self.port = free_port()
        self.appendonly = appendonly
        self.popen: subprocess.Popen[bytes] | None = None

    @property
    def url(self) -> str:
        return f"redis://127.0.0.1:{self.port}/0"

    def start(self) -> float:
        argv = ["redis-server", "--port", str(self.port), "--bind", "127.0.0.1"]
        argv += ["--dir", str(self.dir), "--save", "", "--maxmemory-policy", "noeviction"]
        argv += ["--appendonly", "yes" if self.appendonly else "no"]
        self.popen = subprocess.Popen(argv, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        return wait_port(self.port)

    def signal(self, sig: int) -> None:
        assert self.popen is not None
        self.popen.send_signal(sig)
        self.popen.wait(timeout=30)
        wait_port(self.port, up=False)

    def stop(self) -> None:
        if self.popen is not None and self.popen.poll() is None:
            self.signal(signal.SIGTERM)


def _migrations_digest() -> str:
    digest = hashlib.sha256()
    for path in sorted(ROOT.glob("*/migrations/*.py")):
        digest.update(str(path.relative_to(ROOT)).encode())
        digest.update(path.read_bytes())
    return digest.hexdigest()[:16]


def _prune_templates(keep: Path) -> None:
    """Drop templates of older migration sets (an hour unused: no row still copies them)."""
    for path in TEMPLATE_ROOT.iterdir():
        if path != keep and path.is_dir() and time.time() - path.stat().st_mtime > 3600:
            shutil.rmtree(path, ignore_errors=True)


class Postgres:
    """A PostgreSQL 15 cluster in a temporary directory, migrated (copied from a cached template
    cluster that is initdb'd and migrated once per set of migration files)."""

    def __init__(self, workdir: Path) -> None:
        self.dir = workdir / "pgdata"
        self.socket_dir = workdir / "pgsocket"
        self.port = free_port()

    @property
    def url(self) -> str:
        return f"postgres://postgres@127.0.0.1:{self.port}/fleet"

    def _ctl(self, *args: str, data: Path | None = None) -> None:
        subprocess.run(
            [*_as_user("postgres"), str(PG_BIN / "pg_ctl"), "-D", str(data or self.dir), *args],
            check=True,
            stdout=subprocess.DEVNULL,
            stderr=subprocess.DEVNULL,
        )

    def _options(self, port: int) -> str:
        return f"-p {port} -k {self.socket_dir} -c fsync=off -c listen_addresses=127.0.0.1"

    def create(self) -> None:
        """Copy the migrated template cluster (making it first if needed)."""
        template = self._template()
        shutil.copytree(template, self.dir, symlinks=True)
        self.socket_dir.mkdir(parents=True, exist_ok=True)
        _chown(self.socket_dir, "postgres")
        if os.geteuid() == 0:
            subprocess.run(["chown", "-R", "postgres:postgres", str(self.dir)], check=True)

    def _template(self) -> Path:
        template = TEMPLATE_ROOT / _migrations_digest()
        if (template / "PG_VERSION").exists():
            return template
        TEMPLATE_ROOT.mkdir(parents=True, exist_ok=True)
        _chown(TEMPLATE_ROOT, "postgres")
        with (TEMPLATE_ROOT / ".lock").open("w") as lock:  # one build at a time; others wait
            fcntl.flock(lock, fcntl.LOCK_EX)
            if not (template / "PG_VERSION").exists():
                self._build_template(template)
                _prune_templates(keep=template)
        return template

    def _build_template(self, template: Path) -> None:
        building = Path(tempfile.mkdtemp(dir=TEMPLATE_ROOT, prefix="building-"))
        _chown(building, "postgres")
        data = building / "data"
        subprocess.run(
            [*_as_user("postgres"), str(PG_BIN / "initdb"), "-D", str(data), "-A", "trust"],
            check=True,
            stdout=subprocess.DEVNULL,
        )
        self.socket_dir.mkdir(parents=True, exist_ok=True)
        _chown(self.socket_dir, "postgres")
        port = free_port()
        self._ctl("-o", self._options(port), "-w", "start", data=data)
        try:
            subprocess.run(
                [*_as_user("postgres"), str(PG_BIN / "createdb"), "-h", "127.0.0.1"]
                + ["-p", str(port), "fleet"],
                check=True,
            )
            env = {**os.environ, "DATABASE_URL": f"postgres://postgres@127.0.0.1:{port}/fleet"}
            env.pop("REDIS_URL", None)
            subprocess.run(
                [sys.executable, "manage.py", "migrate", "--no-input"],
                cwd=ROOT,
                env=env,
                check=True,
                stdout=subprocess.DEVNULL,
            )
        finally:
            self._ctl("-m", "fast", "-w", "stop", data=data)
        data.rename(template)
        shutil.rmtree(building, ignore_errors=True)

    def start(self) -> float:
        started = time.monotonic()
        self._ctl("-o", self._options(self.port), "-w", "-t", "60", "start")
        return time.monotonic() - started

    def postmaster_pid(self) -> int:
        return int((self.dir / "postmaster.pid").read_text().split()[0])

    def stop_immediate(self) -> None:
        """`pg_ctl stop -m immediate`: no shutdown checkpoint, clients cut off."""
        self._ctl("-m", "immediate", "-w", "stop")

    def kill(self) -> None:
        """SIGKILL the postmaster by pid (its children exit once it is gone)."""
        pid = self.postmaster_pid()
        os.kill(pid, signal.SIGKILL)
        deadline = time.monotonic() + 30
        while time.monotonic() < deadline:
            try:
                os.kill(pid, 0)
            except ProcessLookupError:
                break
            time.sleep(0.05)
        wait_port(self.port, up=False)
        # The surviving backends hold the shared memory; wait until they are gone too.
        time.sleep(1.0)

    def stop(self) -> None:
        if (self.dir / "postmaster.pid").exists():
            with contextlib.suppress(subprocess.CalledProcessError):
                self._ctl("-m", "fast", "-w", "stop")


class Stack:
    """Mosquitto + Redis + PostgreSQL of one row, cleaned up by `close()`."""

    def __init__(self, *, appendonly: bool = True) -> None:
        self.workdir = Path(tempfile.mkdtemp(prefix="fleet-faults-"))
        os.chmod(self.workdir, 0o755)
        self.mosquitto = Mosquitto(self.workdir)
        self.redis = Redis(self.workdir, appendonly=appendonly)
        self.postgres = Postgres(self.workdir)

    def start(self) -> None:
        self.postgres.create()
        self.postgres.start()
        self.redis.start()
        self.mosquitto.start()

    def env(self) -> dict[str, str]:
        return {
            "DATABASE_URL": self.postgres.url,
            "REDIS_URL": self.redis.url,
            "MQTT_URL": self.mosquitto.url,
        }

    def close(self) -> None:
        for service in (self.mosquitto, self.redis, self.postgres):
            try:
                service.stop()
            except Exception as exc:  # noqa: BLE001 - cleanup goes on for the others
                print(f"stopping {type(service).__name__}: {exc}", file=sys.stderr)
        shutil.rmtree(self.workdir, ignore_errors=True)
