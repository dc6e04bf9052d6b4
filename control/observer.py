"""Floor observation (alerts, inventory, battery, maintenance) off control's main loop.

A flush used to evaluate the saved snapshots itself: when many vehicles changed at once (a
broker restart, a network blip, control falling behind) that meant one alert write per vehicle
inside the flush, seconds during which control neither synced nor published orders (issue 11,
docs/LOAD.md). `SnapshotObserver` runs the same evaluation on a thread of its own with its own
database connection (Django's connections are per thread). The flush only hands over its
snapshots. Alerts are conditions, so when the observer is behind only the newest snapshot of
each vehicle matters: pending snapshots are coalesced per vehicle, never queued without bound.
"""

import logging
import threading
import time
from collections.abc import Callable, Mapping, Sequence
from typing import Any

from django.db import close_old_connections, connection

logger = logging.getLogger(__name__)

Observe = Callable[[Sequence[Mapping[str, Any]]], None]


class SnapshotObserver:
    """Coalesces flushed snapshots per vehicle and evaluates them on a background thread."""

    def __init__(self, observe: Observe, *, min_interval: float = 0.0) -> None:
        self.observe = observe
        # Seconds from one pass's start to the next: with 1,000 vehicles a pass is about a
        # tenth of control's CPU, and alerts are conditions that a second more does not change
        # (snapshots coalesce meanwhile, as when the observer is behind).
        self.min_interval = min_interval
        self._pending: dict[Any, Mapping[str, Any]] = {}
        self._requested = False  # a flush happened (the late-order checks run even without rows)
        self._lock = threading.Lock()
        self._wake = threading.Event()
        self._stop = threading.Event()
        self.idle = threading.Event()  # set while nothing is pending (tests, shutdown)
        self.idle.set()
        self.passes = 0
        self.coalesced = 0  # snapshots replaced by a newer one of the same vehicle before use
        self._thread: threading.Thread | None = None

    def submit(self, snapshots: Sequence[Mapping[str, Any]]) -> None:
        """Hand over one flush's snapshots (rows are complete, so the newest one wins)."""
        with self._lock:
            for snapshot in snapshots:
                if snapshot["pk"] in self._pending:
                    self.coalesced += 1
                self._pending[snapshot["pk"]] = snapshot
            self._requested = True
            self.idle.clear()
        self._wake.set()

    def run_pending(self) -> bool:
        """Evaluate what is pending now, on the calling thread; False if nothing was."""
        with self._lock:
            if not self._requested:
                self.idle.set()
                return False
            snapshots = list(self._pending.values())
            self._pending, self._requested = {}, False
        close_old_connections()
        try:
            self.observe(snapshots)
        except Exception:  # the observers never raise; this guards the thread all the same
            logger.exception("floor observation failed; the next flush retries")
        self.passes += 1
        return True

    def start(self, *, until: threading.Event | None = None) -> threading.Thread:
        """Run on a daemon thread until `stop()` or `until` is set."""

        def run() -> None:
            try:
                while not self._stop.is_set() and not (until is not None and until.is_set()):
                    if not self._wake.wait(0.5):
                        continue
                    self._wake.clear()
                    started = time.monotonic()
                    while self.run_pending():
                        rest = self.min_interval - (time.monotonic() - started)
                        if rest > 0 and self._stop.wait(rest):
                            break
                        started = time.monotonic()
            finally:
                connection.close()  # this thread's own connection

        self._thread = threading.Thread(target=run, name="control-observer", daemon=True)
        self._thread.start()
        return self._thread

    def stop(self, timeout: float = 5.0) -> None:
        self._stop.set()
        self._wake.set()
        if self._thread is not None:
            self._thread.join(timeout)

    def wait_idle(self, timeout: float = 10.0) -> bool:
        return self.idle.wait(timeout)
