"""Header helpers: per-topic ``headerId`` counters and protocol timestamps."""

from __future__ import annotations

import re
import threading
from datetime import UTC, datetime
from typing import TypedDict

from vda5050.enums import TopicKind
from vda5050.errors import TimestampError
from vda5050.topics import parse_kind
from vda5050.versions import major_of

__all__ = [
    "HEADER_ID_MODULUS",
    "HeaderCounter",
    "HeaderFields",
    "format_timestamp",
    "now_timestamp",
    "parse_timestamp",
]

#: headerId is a uint32, so the counter wraps to 0 after 2**32 - 1.
HEADER_ID_MODULUS = 2**32

_Key = tuple[str, str, TopicKind]


class HeaderFields(TypedDict):
    """Header keywords shared by every message Struct (``**fields`` into the constructor)."""

    header_id: int
    timestamp: str
    version: str
    manufacturer: str
    serial_number: str


class HeaderCounter:
    """Hands out ``headerId`` values per (manufacturer, serial number, topic kind).

    REFERENCE §2: the headerId is counted per topic and incremented with every *sent*
    message, so master control keeps one counter per vehicle × topic. Each counter starts
    at 0 and wraps at 2**32. Thread-safe, because MQTT callbacks and request handlers may
    publish concurrently.
    """

    def __init__(self) -> None:
        self._next: dict[_Key, int] = {}
        self._lock = threading.Lock()

    @staticmethod
    def _key(manufacturer: str, serial_number: str, kind: TopicKind | str) -> _Key:
        # Normalising to TopicKind rejects typos such as "instantaction" early; every
        # version's kinds are accepted (3.0 adds zoneSet and responses).
        return (manufacturer, serial_number, parse_kind(kind, None))

    def next_id(self, manufacturer: str, serial_number: str, kind: TopicKind | str) -> int:
        """Return the headerId for the next message on this topic and advance the counter."""
        key = self._key(manufacturer, serial_number, kind)
        with self._lock:
            value = self._next.get(key, 0)
            self._next[key] = (value + 1) % HEADER_ID_MODULUS
            return value

    def header(
        self, manufacturer: str, serial_number: str, kind: TopicKind | str, version: str
    ) -> HeaderFields:
        """The five header fields of the next message on this topic, as Struct keywords."""
        return HeaderFields(
            header_id=self.next_id(manufacturer, serial_number, kind),
            timestamp=now_timestamp(version),
            version=version,
            manufacturer=manufacturer,
            serial_number=serial_number,
        )

    def peek(self, manufacturer: str, serial_number: str, kind: TopicKind | str) -> int:
        """Return the headerId :meth:`next_id` would hand out, without advancing."""
        key = self._key(manufacturer, serial_number, kind)
        with self._lock:
            return self._next.get(key, 0)

    def set_next(
        self, manufacturer: str, serial_number: str, kind: TopicKind | str, value: int
    ) -> None:
        """Make :meth:`next_id` return ``value`` next (e.g. to resume after a restart)."""
        if isinstance(value, bool) or not isinstance(value, int):
            raise TypeError("headerId must be an int")
        if not 0 <= value < HEADER_ID_MODULUS:
            raise ValueError(f"headerId must be in [0, 2**32), got {value}")
        key = self._key(manufacturer, serial_number, kind)
        with self._lock:
            self._next[key] = value

    def reset(
        self, manufacturer: str, serial_number: str, kind: TopicKind | str | None = None
    ) -> None:
        """Restart one topic (or, with ``kind=None``, every topic) of a vehicle at 0."""
        with self._lock:
            if kind is not None:
                self._next.pop(self._key(manufacturer, serial_number, kind), None)
                return
            for key in [k for k in self._next if k[:2] == (manufacturer, serial_number)]:
                del self._next[key]


def format_timestamp(dt: datetime, version: str) -> str:
    """Format ``dt`` as a protocol timestamp in UTC.

    2.x: ``YYYY-MM-DDTHH:mm:ss.ffZ`` (hundredths); 3.x: ``YYYY-MM-DDTHH:mm:ss.fffZ``.
    Fractions are truncated, not rounded, so a timestamp never lies in the future nor
    rolls over into the next second/day.

    Raises:
        TimestampError: if ``dt`` is naive (its time zone would be a guess).
        VersionError: if ``version`` is malformed.
    """
    if dt.tzinfo is None or dt.utcoffset() is None:
        raise TimestampError("naive datetime: pass an aware datetime (e.g. tz=UTC)")
    digits = 2 if major_of(version) < 3 else 3
    try:
        utc = dt.astimezone(UTC)
    except OverflowError:
        raise TimestampError(f"{dt!r} is out of range in UTC") from None
    fraction = f"{utc.microsecond:06d}"[:digits]
    # Explicit widths: strftime("%Y") does not zero-pad years below 1000 on every libc.
    return (
        f"{utc.year:04d}-{utc.month:02d}-{utc.day:02d}T"
        f"{utc.hour:02d}:{utc.minute:02d}:{utc.second:02d}.{fraction}Z"
    )


def now_timestamp(version: str) -> str:
    """Return the current time formatted by :func:`format_timestamp`."""
    return format_timestamp(datetime.now(UTC), version)


# Python's fromisoformat accepts at most 6 fractional digits; longer fractions are legal ISO.
_LONG_FRACTION_RE = re.compile(r"([.,]\d{6})\d+")


def parse_timestamp(text: str) -> datetime:
    """Parse an ISO 8601 timestamp into an aware UTC datetime.

    Tolerant on purpose (vehicles differ): any number of fractional digits, ``Z``/``z``
    or a numeric offset, ``T`` or space separator. A timestamp without offset is taken as
    UTC, which is what the protocol mandates.

    Raises:
        TimestampError: if ``text`` is not an ISO 8601 date/time.
    """
    if not isinstance(text, str):
        raise TimestampError(f"timestamp must be a string, got {type(text).__name__}")
    # Uppercasing is safe: the only letters in ISO 8601 timestamps are T, Z and W.
    normalised = _LONG_FRACTION_RE.sub(r"\1", text.strip().upper())
    try:
        parsed = datetime.fromisoformat(normalised)
        if parsed.tzinfo is None:
            return parsed.replace(tzinfo=UTC)
        return parsed.astimezone(UTC)
    except (ValueError, OverflowError) as exc:
        raise TimestampError(f"invalid ISO 8601 timestamp {text!r}: {exc}") from None
