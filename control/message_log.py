"""The raw VDA 5050 messages of each vehicle, both directions, for the vehicle page.

`control` is the only process that sees the wire, so it keeps, per vehicle, the latest payload
and its time for every topic (state, visualization, connection, factsheet in; order,
instantActions out), a short ring of recent messages (visualizations, up to 10 a second, only
while watched) and the latest order updates (an update repeats only its stitching node, so a
page needs them all to draw the order). Browsers get them only for *watched*
vehicles: a vehicle page asks `control` to watch its vehicle and renews the watch while it is
open; a watch that is not renewed expires, so `control` never streams the whole fleet.

Recording is on the hot path: a dict lookup, a deque append and a reference to the payload
bytes (no copy, no decoding); text is made only for what is streamed.
"""

import itertools
import time
from collections import deque
from dataclasses import dataclass, field
from typing import Any, NamedTuple

IN, OUT = "in", "out"  # vehicle → master, master → vehicle
RING_SIZE = 20  # recent messages kept per vehicle, watched or not (memory: 20 × message size)
ORDERS_KEPT = 10  # the latest order messages per vehicle: a page draws an order from its updates
WATCH_SECONDS = 30.0  # a page renews its watch well before this
MAX_STREAMED_BYTES = 256_000  # larger payloads are cut (a factsheet or a huge order)

VehicleKey = tuple[str, str]


class LoggedMessage(NamedTuple):
    """One message as it crossed the wire, numbered so browsers can drop duplicates."""

    seq: int
    at: float  # wall clock, seconds since the epoch
    direction: str  # IN or OUT
    topic: str  # the topic kind: state, order, …
    payload: bytes
    note: str = ""  # why control dropped it, if it did

    def as_event(self) -> dict[str, Any]:
        text = self.payload[:MAX_STREAMED_BYTES].decode("utf-8", errors="replace")
        return {
            "seq": self.seq,
            "at": self.at,
            "direction": self.direction,
            "topic": str(self.topic),  # a StrEnum on the hot path
            "json": text,
            "truncated": len(self.payload) > MAX_STREAMED_BYTES,
            "note": self.note,
        }


# On the hot path a message is stored as a plain tuple in LoggedMessage's field order: building
# a tuple costs a third of building a named tuple or a dataclass; reads wrap it.
_Entry = tuple[int, float, str, str, bytes, str]


@dataclass(slots=True)
class _VehicleLog:
    latest: dict[str, _Entry] = field(default_factory=dict)
    ring: deque[_Entry] = field(default_factory=lambda: deque(maxlen=RING_SIZE))
    orders: deque[_Entry] = field(default_factory=lambda: deque(maxlen=ORDERS_KEPT))
    streamed_seq: int = 0  # the highest seq already streamed to watchers


@dataclass
class WatchBatch:
    """What to stream for one watched vehicle: new messages, and on a (re)join the latest
    message of every topic, the ring and the latest order updates, so a freshly opened page is
    filled at once and can draw the whole current order."""

    key: VehicleKey
    messages: list[dict[str, Any]]
    latest: dict[str, dict[str, Any]] | None = None


class MessageLog:
    """Latest message per topic and a bounded ring per vehicle; watches with expiry.

    Not thread-safe on its own: `control` calls it under the controller's lock.
    """

    def __init__(self, ring_size: int = RING_SIZE, clock: Any = time.monotonic) -> None:
        self.ring_size = ring_size
        self.clock = clock
        self._logs: dict[VehicleKey, _VehicleLog] = {}
        self._watches: dict[VehicleKey, float] = {}  # key -> monotonic expiry
        self._full_requested: set[VehicleKey] = set()
        self._seq = itertools.count(1)

    def record(
        self, key: VehicleKey, direction: str, topic: str, payload: bytes, note: str = ""
    ) -> None:
        """Remember one message (call it for known vehicles only: keys are never dropped)."""
        log = self._logs.get(key)
        if log is None:
            log = self._logs[key] = _VehicleLog(ring=deque(maxlen=self.ring_size))
        entry = (next(self._seq), time.time(), direction, topic, payload, note)
        log.latest[topic] = entry
        if topic == "visualization" and key not in self._watches:
            return  # up to 10 a second: in the ring only while a page shows them
        log.ring.append(entry)
        if topic == "order":
            log.orders.append(entry)

    def latest(self, key: VehicleKey) -> dict[str, LoggedMessage]:
        log = self._logs.get(key)
        return {t: LoggedMessage._make(e) for t, e in log.latest.items()} if log else {}

    def recent(self, key: VehicleKey) -> list[LoggedMessage]:
        log = self._logs.get(key)
        return [LoggedMessage._make(e) for e in log.ring] if log else []

    def watch(self, key: VehicleKey, *, seconds: float = WATCH_SECONDS, full: bool = False) -> None:
        """Stream `key` for `seconds` more; `full` also resends what is known (a page joined)."""
        seconds = min(max(seconds, 1.0), 5 * WATCH_SECONDS)  # a command cannot pin it forever
        self._watches[key] = max(self._watches.get(key, 0.0), self.clock() + seconds)
        if full:
            self._full_requested.add(key)

    def watched(self) -> list[VehicleKey]:
        """The keys watched now; expired watches are forgotten here."""
        now = self.clock()
        for key in [k for k, expiry in self._watches.items() if expiry <= now]:
            del self._watches[key]
            self._full_requested.discard(key)
        return list(self._watches)

    def collect(self) -> list[WatchBatch]:
        """For each watched vehicle, what its pages have not seen yet (nothing if nothing)."""
        batches = []
        for key in self.watched():
            log = self._logs.get(key) or _VehicleLog()
            full = key in self._full_requested
            self._full_requested.discard(key)
            since = 0 if full else log.streamed_seq
            entries = {e[0]: e for e in log.orders} if full else {}
            entries.update((e[0], e) for e in log.ring if e[0] > since)
            fresh = [LoggedMessage._make(entries[seq]) for seq in sorted(entries)]
            if fresh:
                log.streamed_seq = max(log.streamed_seq, fresh[-1].seq)
            if not (fresh or full):
                continue
            latest = None
            if full:
                latest = {str(t): LoggedMessage._make(e).as_event() for t, e in log.latest.items()}
            batches.append(WatchBatch(key, [m.as_event() for m in fresh], latest))
        return batches
