"""Leadership of `control`: one active process, the others on standby (issue 11 item 3).

The leader holds a PostgreSQL session-level advisory lock on its own psycopg connection (not
Django's, which control closes and reopens freely). Each new leader takes the next number of a
sequence, its *fencing number*, and renews a *lease* every `renew_every` seconds with a cheap
query on the lock connection. Publishing is allowed only while the lease runs, checked against
the monotonic clock (no database round trip per publish):

- a leader frozen by SIGSTOP wakes with an expired lease and sends nothing before its renewal
  thread has asked the database again; the server has meanwhile ended the frozen session (the
  lock connection sits idle in an open transaction, and `idle_in_transaction_session_timeout` is
  longer than the lease), so the renewal fails and the process steps down to standby;
- when the database goes away (restart, network) the renewal fails: the leader steps down at
  once and competes for the lock again like a standby;
- a new leader waits `guard` seconds (longer than the lease) after taking the lock before it
  publishes, so an old leader whose session ended without it noticing has seen its lease run out.

VDA 5050 vehicles cannot check a fencing token, so these local timings are the fence; the
invariants `server_timeout > lease` and `guard > lease` are checked in `LeaseTimes`. The timings
come from settings (`CONTROL_LEASE`, docs/RELIABILITY_RESULTS.md "Standby"): the defaults let
the renewal thread be starved for ~5 s (a loaded host) before the server ends the session, and
still keep a frozen leader's failover near 12 s. A process that stepped down waits `rejoin_after`
before it competes again, so a healthy standby takes over before a starved process leads anew.
"""

import logging
import os
import socket
import threading
import time
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import Any

import psycopg

logger = logging.getLogger(__name__)

LOCK_KEY = 5050_0001  # the advisory lock of the control leader (per database)
FENCING_SEQUENCE = "control_leader_fencing"
APPLICATION_NAME = "fleet-control-leader"


@dataclass(frozen=True)
class LeaseTimes:
    """The leadership timings in seconds; see the module docstring for why each order holds."""

    # Renewing often keeps the lease (and the server's idle-in-transaction clock) fresh while the
    # renewal thread gets the CPU only now and then: a starved thread loses less per gap.
    renew_every: float = 0.5
    lease: float = 5.0
    server_timeout: float = 6.0  # the server ends a silent leader's session after this
    guard: float = 5.5  # a new leader waits this long after taking the lock
    retry_every: float = 0.5  # a standby tries the lock (and a lost database) this often
    rejoin_after: float = 2.0  # a process that stepped down waits this long before competing

    def __post_init__(self) -> None:
        if not self.renew_every < self.lease < min(self.server_timeout, self.guard):
            raise ValueError(f"need renew_every < lease < server_timeout and guard: {self}")
        if self.retry_every <= 0 or self.rejoin_after < 0:
            raise ValueError(f"need retry_every > 0 and rejoin_after >= 0: {self}")

    @classmethod
    def from_settings(cls, values: Mapping[str, float]) -> "LeaseTimes":
        """From `settings.CONTROL_LEASE` (keys RENEW_EVERY, LEASE, SERVER_TIMEOUT, GUARD,
        RETRY_EVERY, REJOIN_AFTER; a missing key keeps its default)."""
        names = {f.upper(): f for f in cls.__dataclass_fields__}
        unknown = set(values) - names.keys()
        if unknown:
            raise ValueError(f"unknown CONTROL_LEASE keys: {sorted(unknown)}")
        return cls(**{names[key]: float(value) for key, value in values.items()})


def conninfo_from_settings(database: dict[str, Any]) -> str:
    """A libpq connection string for Django's `DATABASES['default']`."""
    parts = {
        "dbname": database.get("NAME"),
        "user": database.get("USER"),
        "password": database.get("PASSWORD"),
        "host": database.get("HOST"),
        "port": database.get("PORT"),
    }
    return psycopg.conninfo.make_conninfo(**{k: str(v) for k, v in parts.items() if v})


class Leadership:
    """Competes for the leader lock in a background thread and keeps the lease while it leads.

    `holds_lease()` is what the publisher asks before every message; `wait_until_leading()` is
    what a standby process blocks in; `lost` is set when a leader steps down.
    """

    def __init__(
        self,
        conninfo: str,
        times: LeaseTimes | None = None,
        *,
        lock_key: int = LOCK_KEY,
        clock: Callable[[], float] = time.monotonic,
    ) -> None:
        self.conninfo, self.times, self.lock_key, self.clock = (
            conninfo,
            times or LeaseTimes(),
            lock_key,
            clock,
        )
        self.identity = f"{socket.gethostname()}:{os.getpid()}"
        self.fencing: int | None = None
        self.database_ok = False
        self.lost = threading.Event()
        self._leading = threading.Event()
        self._stop = threading.Event()
        self._lease_until = 0.0
        self._publish_from = 0.0
        self._conn: psycopg.Connection[Any] | None = None
        self._thread: threading.Thread | None = None
        self._rejoin_at = 0.0  # after a step-down: when this process competes again
        self.late_renewals = 0  # renewals that came after the lease had run out (starvation)

    # --- asked by the other threads ------------------------------------------------------------

    def holds_lease(self) -> bool:
        """Whether this process may publish now: leading, past the guard, lease not expired."""
        now = self.clock()
        return self._leading.is_set() and self._publish_from <= now < self._lease_until

    @property
    def role(self) -> str:
        return "leader" if self._leading.is_set() else "standby"

    def wait_until_leading(self, stop: threading.Event, poll: float = 0.2) -> bool:
        """Block until this process leads and its guard time is over; False if `stop` was set."""
        while not stop.is_set():
            if self._leading.is_set() and self.clock() >= self._publish_from:
                return True
            stop.wait(poll)
        return False

    def status(self) -> dict[str, Any]:
        """Role, fencing number and lease state for the health endpoint."""
        remaining = self._lease_until - self.clock() if self._leading.is_set() else 0.0
        return {
            "role": self.role,
            "fencing": self.fencing if self._leading.is_set() else None,
            "lease_remaining": round(max(remaining, 0.0), 2),
            "holds_lease": self.holds_lease(),
            "database_ok": self.database_ok,
            "identity": self.identity,
            "late_renewals": self.late_renewals,
        }

    # --- lifecycle -----------------------------------------------------------------------------

    def start(self) -> None:
        self._thread = threading.Thread(target=self._run, name="control-leadership", daemon=True)
        self._thread.start()

    def stop(self) -> None:
        """Stop competing; a leader releases the lock by closing its session."""
        self._stop.set()
        if self._thread is not None:
            self._thread.join(timeout=self.times.renew_every + 5)
        self._step_down("stopped", close=True)

    # --- the background thread -----------------------------------------------------------------

    def _run(self) -> None:
        while not self._stop.is_set():
            if self._leading.is_set():
                self._renew()
                self._stop.wait(self.times.renew_every)
            elif self.clock() < self._rejoin_at:
                self._stop.wait(min(self.times.retry_every, self._rejoin_at - self.clock()))
            else:
                self._try_acquire()
                if not self._leading.is_set():
                    self._stop.wait(self.times.retry_every)

    def _connect(self) -> psycopg.Connection[Any]:
        timeout_ms = int(self.times.server_timeout * 1000)
        options = (
            f"-c idle_in_transaction_session_timeout={timeout_ms} "
            f"-c statement_timeout={timeout_ms} "
            # the server also drops the session of a leader whose host vanished
            "-c tcp_keepalives_idle=2 -c tcp_keepalives_interval=1 -c tcp_keepalives_count=2"
        )
        return psycopg.connect(
            self.conninfo,
            autocommit=True,
            connect_timeout=max(2, int(self.times.lease)),
            application_name=APPLICATION_NAME,
            options=options,
            keepalives=1,
            keepalives_idle=2,
            keepalives_interval=1,
            keepalives_count=2,
        )

    def _try_acquire(self) -> None:
        try:
            if self._conn is None or self._conn.closed:
                self._conn = self._connect()
            conn = self._conn
            sent = self.clock()
            row = conn.execute("SELECT pg_try_advisory_lock(%s)", (self.lock_key,)).fetchone()
            self.database_ok = True
            if not row or not row[0]:
                return
            conn.execute(f"CREATE SEQUENCE IF NOT EXISTS {FENCING_SEQUENCE}")  # under the lock
            fencing = conn.execute(f"SELECT nextval('{FENCING_SEQUENCE}')").fetchone()
            # From here the lock connection stays inside one open transaction, so that a silent
            # (frozen) leader's session is ended by idle_in_transaction_session_timeout.
            conn.autocommit = False
            conn.execute("SELECT 1")
        except psycopg.Error as error:
            self.database_ok = False
            logger.warning("leadership: database unavailable (%s)", str(error).strip())
            self._close()
            return
        self.fencing = int(fencing[0]) if fencing else None
        self._lease_until = sent + self.times.lease
        self._publish_from = self.clock() + self.times.guard
        self.lost.clear()
        self._leading.set()
        logger.info(
            "leadership: took the lock, fencing number %s; publishing in %.1f s",
            self.fencing,
            self.times.guard,
        )

    def _renew(self) -> None:
        conn = self._conn
        sent = self.clock()
        try:
            if conn is None:
                raise psycopg.OperationalError("no lock connection")
            row = conn.execute(
                "SELECT count(*) FROM pg_locks WHERE locktype = 'advisory' AND granted"
                " AND pid = pg_backend_pid() AND objid = %s",
                (self.lock_key & 0xFFFFFFFF,),
            ).fetchone()
            if not row or row[0] < 1:
                raise psycopg.OperationalError("the advisory lock is no longer held")
        except psycopg.Error as error:
            self.database_ok = False
            self._step_down(f"renewal failed: {str(error).strip()}", close=True)
            return
        self.database_ok = True
        if sent >= self._lease_until:  # the thread got no CPU for a while: publishing paused
            self.late_renewals += 1
            logger.warning(
                "leadership: renewal %.1f s after the lease ran out (renewal thread starved?)",
                sent - self._lease_until,
            )
        self._lease_until = sent + self.times.lease

    def _step_down(self, reason: str, *, close: bool) -> None:
        was_leading = self._leading.is_set()
        self._leading.clear()
        self._lease_until = 0.0
        if close:
            self._close()
        if was_leading:
            logger.warning("leadership: stepped down (fencing %s): %s", self.fencing, reason)
            self._rejoin_at = self.clock() + self.times.rejoin_after
            self.lost.set()

    def _close(self) -> None:
        conn, self._conn = self._conn, None
        if conn is not None:
            try:
                conn.close()
            except psycopg.Error:
                logger.debug("leadership: closing the lock connection failed", exc_info=True)
