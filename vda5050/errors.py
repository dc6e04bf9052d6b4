"""Exception hierarchy of the :mod:`vda5050` package.

Everything the package raises on bad input derives from :class:`VDA5050Error`, so callers
handling untrusted MQTT traffic need exactly one ``except`` clause.
"""

from __future__ import annotations


class VDA5050Error(Exception):
    """Base class of all errors raised by the :mod:`vda5050` package."""


class TopicError(VDA5050Error):
    """An MQTT topic (or one of its levels) does not follow the VDA 5050 topic rules."""


class VersionError(VDA5050Error):
    """A protocol version string is malformed or not supported."""


class TimestampError(VDA5050Error):
    """A timestamp cannot be formatted or parsed."""


class EncodeError(VDA5050Error):
    """A message cannot be encoded to JSON (e.g. it contains NaN or Infinity)."""

    def __init__(self, reason: str, path: str | None = None) -> None:
        self.reason = reason
        self.path = path
        where = f" at {path}" if path else ""
        super().__init__(f"cannot encode message{where}: {reason}")


class DecodeError(VDA5050Error):
    """A payload is not a valid VDA 5050 message of the expected topic kind.

    Attributes:
        kind: the topic kind the payload was decoded as (e.g. ``"state"``).
        path: JSON path of the offending element in msgspec style
            (``$.nodes[2].nodeId``), or ``None`` if the error is not tied to one element.
        reason: human-readable description of what is wrong.
    """

    def __init__(self, kind: str, reason: str, path: str | None = None) -> None:
        self.kind = kind
        self.reason = reason
        self.path = path
        where = f" at {path}" if path else ""
        super().__init__(f"invalid {kind} message{where}: {reason}")
