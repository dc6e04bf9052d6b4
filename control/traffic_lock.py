"""Letting the controller's lock go while a route search runs (used by control/traffic_link.py).

A route search takes milliseconds, up to a hundred in congestion (docs/LOAD.md). Only two
callers let the lock go for it: an order's start and the tick's re-plans, each a single search
whose result the manager checks against the reservation table once the lock is back
(`TrafficManager.unlocked`). Searches inside composite changes (block, restore, re-adoption)
keep it: nobody may see those half done.
"""

import threading
from collections.abc import Iterator
from contextlib import contextmanager
from typing import Any


class SearchLock:
    """The controller's lock as route searches see it: a search lets it go only inside
    `searches_let_go()` on the same thread; anywhere else it keeps it."""

    def __init__(self, lock: Any) -> None:
        self.lock = lock  # the controller's RLock
        self._allowed = threading.local()  # .value: this thread's searches may let go now

    @contextmanager
    def searches_let_go(self) -> Iterator[None]:
        """Searches this thread runs in the block let the lock go."""
        before = getattr(self._allowed, "value", False)
        self._allowed.value = True
        try:
            yield
        finally:
            self._allowed.value = before

    @contextmanager
    def let_go_if_allowed(self) -> Iterator[None]:
        """What a manager's search runs under (`TrafficManager.unlocked`)."""
        if getattr(self._allowed, "value", False):
            with let_go(self.lock):
                yield
        else:
            yield


@contextmanager
def let_go(lock: Any) -> Iterator[None]:
    """Release `lock`, an RLock this thread may hold (at any depth), for the block.

    Uses the RLock methods `threading.Condition` uses for the same purpose (`_is_owned`,
    `_release_save`, `_acquire_restore`); a lock without them is kept."""
    if not getattr(lock, "_is_owned", lambda: False)():
        yield
        return
    saved = lock._release_save()
    try:
        yield
    finally:
        lock._acquire_restore(saved)
