"""The protocol session with one vehicle: liveness, header ids and clock skew.

Pure logic, driven by the controller with the receive time. REFERENCE H.38: the retained
`connection` topic is not a health check (after a broker crash it can say ONLINE for a vehicle
that is gone), so liveness also needs a state timeout. REFERENCE §2: header ids count per topic;
we drop duplicates and older messages of the same connection, count gaps, and start counting
afresh after a new ONLINE. Vehicle timestamps are never used for ordering, only to show skew.

Liveness probe: a vehicle may declare up to 30 s between states, so its state timeout alone
notices a freeze only after 35 s, and the broker's will after 22-29 s. A vehicle silent for
`probe_after` seconds is sent one stateRequest (REFERENCE §4; the controller sends it only if
the vehicle takes it, E.25, I.39); no state within PROBE_GRACE and it is UNREACHABLE.
"""

import enum
from collections import Counter
from dataclasses import dataclass, field

DEFAULT_STATE_INTERVAL = 30.0  # seconds; REFERENCE F.30 "at the latest every 30 s"
TIMEOUT_GRACE = 5.0  # seconds on top of the interval before a vehicle counts as unreachable
PROBE_AFTER = 10.0  # s of silence before a stateRequest probe (FLEET_CONTROL LIVENESS_PROBE_AFTER)
PROBE_GRACE = 5.0  # s a probed vehicle has to answer before it counts as unreachable
HEADER_WRAP = 2**32


class Verdict(enum.Enum):
    APPLY = "apply"
    DUPLICATE = "duplicate"
    STALE = "stale"


class Link(enum.StrEnum):
    """What we believe about the vehicle's connection (stored as `robots.Vehicle.connection`)."""

    UNKNOWN = "UNKNOWN"
    ONLINE = "ONLINE"
    UNREACHABLE = "UNREACHABLE"
    OFFLINE = "OFFLINE"
    CONNECTIONBROKEN = "CONNECTIONBROKEN"


# 3.0 spellings and states map onto the 2.x ones we store.
_REPORTED = {"CONNECTION_BROKEN": Link.CONNECTIONBROKEN, "HIBERNATING": Link.ONLINE}


@dataclass
class ProtocolSession:
    """Liveness and message-order bookkeeping for one vehicle."""

    reported: Link = Link.UNKNOWN
    last_state_at: float | None = None  # our monotonic clock
    last_alive_at: float | None = None  # last state or ONLINE, our monotonic clock
    state_interval: float = DEFAULT_STATE_INTERVAL
    clock_skew: float | None = None  # seconds our clock is ahead of the vehicle's
    # 3.0 HIBERNATING: connected but sends no states by design, so never probed. Only a
    # connection message ends it, not a state (the last one may arrive just after it).
    hibernating: bool = False
    probe_deadline: float | None = None  # a stateRequest probe is out: answer by then
    counters: Counter[str] = field(default_factory=Counter)
    _last_header: dict[str, int] = field(default_factory=dict)
    _last_online: tuple[int, str] | None = None  # (headerId, timestamp) of the last ONLINE

    def check_header(self, kind: str, header_id: int) -> Verdict:
        """Whether a message with `header_id` on topic `kind` is new, a duplicate or stale."""
        last = self._last_header.get(kind)
        if last is not None:
            ahead = (header_id - last) % HEADER_WRAP  # wrap-around safe distance
            if ahead == 0:
                self.counters["duplicates"] += 1
                return Verdict.DUPLICATE
            if ahead > HEADER_WRAP // 2:
                self.counters["stale"] += 1
                return Verdict.STALE
            if ahead > 1:
                self.counters["gaps"] += ahead - 1
        self._last_header[kind] = header_id
        return Verdict.APPLY

    def on_connection(
        self, reported: str, now: float, identity: tuple[int, str] | None = None
    ) -> bool:
        """Take a `connection` message (`identity`: its headerId and timestamp); True when the
        vehicle (re)connected and needs a stateRequest and factsheetRequest to reconcile."""
        link = _REPORTED.get(reported) or Link(reported)
        reconnected = link is Link.ONLINE and self.link(now) is not Link.ONLINE
        self.hibernating = reported == "HIBERNATING"
        if link is Link.ONLINE:
            # A new connection may restart header ids at 0: accept whatever comes next. The
            # same retained ONLINE again (our own re-subscribe after a broker reconnect) is no
            # new connection: forgetting the header ids then let held-back states through.
            if identity is None or identity != self._last_online:
                self._last_header.clear()
            self._last_online = identity
            self.last_alive_at = now
            self.probe_deadline = None  # alive: the silence episode is over
        self.reported = link
        return reconnected

    def on_state(self, now: float, skew: float | None) -> bool:
        """Take a state; True if the vehicle was silent or unknown before (reconcile it)."""
        woke_up = self.last_state_at is None or self.timed_out(now)
        self.last_state_at = self.last_alive_at = now
        self.probe_deadline = None  # answered (or just talking): the silence episode is over
        self.clock_skew = skew
        if self.reported is not Link.ONLINE:
            # A vehicle that sends state is connected, whatever a stale retained message said.
            self.reported = Link.ONLINE
        return woke_up

    def timed_out(self, now: float) -> bool:
        """No state (nor ONLINE) for longer than the vehicle's state interval plus grace.

        This is how we notice a frozen vehicle (radio loss: its socket stays open) within
        `defaultStateInterval` + 5 s, whatever the broker does. Its last will only comes once
        the broker's keepalive sweep finds it silent for 1.5 × keepalive: with Mosquitto 2.0,
        which sweeps at most every 6 s in whole seconds, 22-29 s after the last packet for the
        usual 15 s keepalive (docs/RELIABILITY_RESULTS.md, link loss). The interval is the
        vehicle's own (factsheet), not a guess: a vehicle declaring 30 s may be silent 30 s.
        """
        if self.last_alive_at is None:
            return False
        if self.probe_deadline is not None and now > self.probe_deadline:
            return True  # probed and no answer in time (see the module docstring)
        return now - self.last_alive_at > self.state_interval + TIMEOUT_GRACE

    def probe_due(self, now: float, after: float = PROBE_AFTER) -> bool:
        """Whether to send this ONLINE vehicle a stateRequest now: silent (no state, no ONLINE)
        for more than `after` seconds (0 = never), not probed yet in this silence episode,
        not hibernating, and declaring a longer state interval than `after` (else its own
        state timeout is as quick). A vehicle may be silent up to its interval, so the probe
        is a question, not a verdict: only no answer within the grace makes it unreachable."""
        return (
            after > 0
            and self.state_interval > after
            and self.probe_deadline is None
            and not self.hibernating
            and self.last_alive_at is not None
            and now - self.last_alive_at > after
            and self.link(now) is Link.ONLINE
        )

    def on_probe(self, now: float, grace: float = PROBE_GRACE) -> None:
        """A stateRequest probe went out at `now`: a state or ONLINE must come within `grace`."""
        self.probe_deadline = now + grace

    def link(self, now: float) -> Link:
        """The connection as the registry and dispatch should see it right now."""
        if self.reported is Link.ONLINE and (self.last_alive_at is None or self.timed_out(now)):
            return Link.UNREACHABLE
        return self.reported
