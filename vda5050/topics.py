"""VDA 5050 MQTT topics: ``interfaceName/majorVersion/manufacturer/serialNumber/topic``.

REFERENCE §2: levels must not contain ``/``, ``+``, ``#`` or ``$`` (MQTT separators and
wildcards, ``$`` prefixes broker-internal topics) and the serial number is restricted to
``A-Za-z0-9_.:-``.
"""

from __future__ import annotations

import re
from dataclasses import dataclass, replace

from vda5050.enums import TopicKind
from vda5050.errors import TopicError
from vda5050.versions import major_version_of

__all__ = ["Topic", "TopicError", "kinds_of", "major_version_of", "parse_kind", "subscription"]

# U+0000 is forbidden anywhere in an MQTT topic name (MQTT 3.1.1 §4.7.3).
_FORBIDDEN_CHARS = frozenset("/+#$\x00")
_SERIAL_RE = re.compile(r"[A-Za-z0-9_.:\-]+")
_MAJOR_LEVEL_RE = re.compile(r"v(\d{1,4})")
_LEVELS = 5

_V2_KINDS = frozenset(TopicKind) - {TopicKind.ZONE_SET, TopicKind.RESPONSES}
_V3_KINDS = frozenset(TopicKind)


def kinds_of(major: int) -> frozenset[TopicKind]:
    """Topic kinds of protocol major version ``major``: from 3 on all eight (``zoneSet`` and
    ``responses`` are new), below 3 the six 2.x kinds (1.1 never sends a factsheet, but
    its topic level stays valid)."""
    return _V3_KINDS if major >= 3 else _V2_KINDS


def _level_major(major_version: str) -> int:
    """Major version number of a topic level such as ``"v3"`` (2 if it is not ``vN``)."""
    match = _MAJOR_LEVEL_RE.fullmatch(major_version)
    return int(match.group(1)) if match else 2


def _check_level(name: str, value: object) -> str:
    """Return ``value`` if it is a valid topic level, else raise :class:`TopicError`."""
    if not isinstance(value, str):
        raise TopicError(f"{name} must be a string, got {type(value).__name__}")
    if not value:
        raise TopicError(f"{name} must not be empty")
    bad = sorted(_FORBIDDEN_CHARS.intersection(value))
    if bad:
        raise TopicError(f"{name} {value!r} contains forbidden characters {bad!r}")
    return value


def parse_kind(value: object, major: int | None = 2) -> TopicKind:
    """Coerce ``value`` (e.g. ``"state"``) to a :class:`TopicKind`.

    ``major`` restricts the result to the kinds of that protocol major version (default 2,
    so ``"zoneSet"`` is rejected unless ``major=3``); ``None`` accepts every known kind.

    Raises:
        TopicError: if ``value`` is not a topic kind of that major version.
    """
    if isinstance(value, str):
        try:
            kind = TopicKind(value)
        except ValueError:
            pass
        else:
            if major is None or kind in kinds_of(major):
                return kind
            raise TopicError(f"topic kind {value!r} does not exist in protocol v{major}")
    raise TopicError(f"unknown topic kind {value!r}")


@dataclass(frozen=True, slots=True)
class Topic:
    """A parsed VDA 5050 topic. Construction validates every level.

    ``kind`` may be passed as a plain string (``"state"``); it is stored as
    :class:`TopicKind`.
    """

    interface_name: str
    major_version: str
    manufacturer: str
    serial_number: str
    kind: TopicKind

    def __post_init__(self) -> None:
        _check_level("interface_name", self.interface_name)
        _check_level("major_version", self.major_version)
        _check_level("manufacturer", self.manufacturer)
        _check_level("serial_number", self.serial_number)
        if not _SERIAL_RE.fullmatch(self.serial_number):
            raise TopicError(f"serial_number {self.serial_number!r} may only contain A-Za-z0-9_.:-")
        # Frozen dataclass: object.__setattr__ is the sanctioned way to normalise in init.
        kind = parse_kind(self.kind, _level_major(self.major_version))
        object.__setattr__(self, "kind", kind)

    @classmethod
    def parse(cls, text: str) -> Topic:
        """Parse ``"uagv/v2/Acme/AGV-1/state"`` into a :class:`Topic`.

        Raises:
            TopicError: if ``text`` does not have exactly five valid levels or the last
                level is not a known topic kind.
        """
        if not isinstance(text, str):
            raise TopicError(f"topic must be a string, got {type(text).__name__}")
        levels = text.split("/")
        if len(levels) != _LEVELS:
            raise TopicError(
                f"topic {text!r} must have {_LEVELS} levels "
                "interfaceName/majorVersion/manufacturer/serialNumber/topic"
            )
        interface_name, major_version, manufacturer, serial_number, kind = levels
        return cls(
            interface_name=interface_name,
            major_version=major_version,
            manufacturer=manufacturer,
            serial_number=serial_number,
            kind=parse_kind(kind, None),  # checked against the major version in __post_init__
        )

    def build(self) -> str:
        """Return the topic string, e.g. ``"uagv/v2/Acme/AGV-1/state"``."""
        return "/".join(
            (
                self.interface_name,
                self.major_version,
                self.manufacturer,
                self.serial_number,
                str(self.kind),
            )
        )

    def __str__(self) -> str:
        return self.build()

    def with_kind(self, kind: TopicKind) -> Topic:
        """Return the topic of the same vehicle for another message kind."""
        return replace(self, kind=kind)


def subscription(
    interface_name: str, major_version: str = "v2", kind: TopicKind | None = None
) -> str:
    """Return the wildcard subscription of the master control.

    ``subscription("uagv")`` → ``"uagv/v2/+/+/#"`` (every topic of every vehicle);
    with ``kind`` → ``"uagv/v2/+/+/state"``; ``kind`` must exist in ``major_version``.
    """
    _check_level("interface_name", interface_name)
    _check_level("major_version", major_version)
    last = "#" if kind is None else str(parse_kind(kind, _level_major(major_version)))
    return f"{interface_name}/{major_version}/+/+/{last}"
