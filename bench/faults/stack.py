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


class _Server:
    """A service process we start ourselves and signal by its `Popen` (Mosquitto, Redis), on a
    free port with its own directory; subclasses say only how it is invoked."""

    def __init__(self, workdir: Path, name: str) -> None:
        self.dir = workdir / name
        self.dir.mkdir(parents=True, exist_ok=True)
        self.port = free_port()
        self.popen: subprocess.Popen[bytes] | None = None

    def argv(self) -> list[str]:
        raise NotImplementedError

    def start(self) -> float:
        """Start it; seconds until its port accepts connections."""
        self.popen = subprocess.Popen(
            self.argv(),
            stdout=subprocess.DEVNULL,
            stderr=subprocess.DEVNULL,
            preexec_fn=_raise_nofile,
        )
        return wait_port(self.port)

    def signal(self, sig: int) -> None:
        """Send `sig` to our process, reap it and wait until its port is closed."""
        assert self.popen is not None
        self.popen.send_signal(sig)
        self.popen.wait(timeout=30)
        wait_port(self.port, up=False)

    def stop(self) -> None:
        if self.popen is not None and self.popen.poll() is None:
            self.signal(signal.SIGTERM)


def _raise_nofile() -> None:
    """Up to 4096 open files (RELIABILITY §0.6: 1024 caps the broker at ~1,000 clients)."""
    import resource

    soft, hard = resource.getrlimit(resource.RLIMIT_NOFILE)
    resource.setrlimit(resource.RLIMIT_NOFILE, (min(4096, hard), hard))


class Mosquitto(_Server):
    """A broker with persistence saved on every change (RELIABILITY §0.2: SIGKILL keeps QoS 1)."""

    def __init__(self, workdir: Path) -> None:
        super().__init__(workdir, "mosquitto")
        _chown(self.dir, "mosquitto")
        self.conf = self.dir / "mosquitto.conf"
        self.conf.write_text(
            f"listener {self.port} 127.0.0.1\nallow_anonymous true\n"
            f"persistence true\npersistence_location {self.dir}/\n"
            "autosave_on_changes true\nautosave_interval 1\n"
            "max_queued_messages 100000\n"
            f"log_dest file {self.dir}/mosquitto.log\n"
        )

    @property
    def url(self) -> str:
        return f"mqtt://127.0.0.1:{self.port}"

    def argv(self) -> list[str]:
        return ["mosquitto", "-c", str(self.conf)]


class Redis(_Server):
    """redis-server with AOF (everysec) in its own directory."""

    def __init__(self, workdir: Path, *, appendonly: bool = True) -> None:
        super().__init__(workdir, "redis")
        self.appendonly = appendonly

    @property
    def url(self) -> str:
        return f"redis://127.0.0.1:{self.port}/0"

    def argv(self) -> list[str]:
        argv = ["redis-server", "--port", str(self.port), "--bind", "127.0.0.1"]
        argv += ["--dir", str(self.dir), "--save", "", "--maxmemory-policy", "noeviction"]
        return argv + ["--appendonly", "yes" if self.appendonly else "no"]


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


def _run_pg(program: str, *args: str, quiet: bool = True) -> None:
    """Run a PostgreSQL program as the `postgres` user; its output is dropped (its errors too
    when `quiet`: a server started by `pg_ctl` inherits them and would hold a pipe open)."""
    subprocess.run(
        [*_as_user("postgres"), str(PG_BIN / program), *args],
        check=True,
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL if quiet else None,
    )


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
        _run_pg("pg_ctl", "-D", str(data or self.dir), *args)

    def _prepare_socket_dir(self) -> None:
        self.socket_dir.mkdir(parents=True, exist_ok=True)
        _chown(self.socket_dir, "postgres")

    def _options(self, port: int) -> str:
        return f"-p {port} -k {self.socket_dir} -c fsync=off -c listen_addresses=127.0.0.1"

    def create(self) -> None:
        """Copy the migrated template cluster (making it first if needed)."""
        template = self._template()
        shutil.copytree(template, self.dir, symlinks=True)
        self._prepare_socket_dir()
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
        _run_pg("initdb", "-D", str(data), "-A", "trust", quiet=False)
        self._prepare_socket_dir()
        port = free_port()
        self._ctl("-o", self._options(port), "-w", "start", data=data)
        try:
            _run_pg("createdb", "-h", "127.0.0.1", "-p", str(port), "fleet", quiet=False)
            env = {**os.environ, "DATABASE_URL": f"postgres://postgres@127.0.0.1:{port}/fleet"}
            # The project's settings, even from pytest: tests.settings would point DATABASE_URL
            # at the shared server (TEST_DATABASE_URL) and migrate that instead.
            env["DJANGO_SETTINGS_MODULE"] = "fleet.settings"
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
