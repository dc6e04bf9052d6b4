"""Protocol version strings (``"2.1.0"``) and the topic major version (``"v2"``)."""

from __future__ import annotations

import re

from vda5050.errors import VersionError

# The header says "[Major].[Minor].[Patch]"; minor/patch are optional here so that a
# sloppy "2.1" from a vehicle still maps to the right major version.
_VERSION_RE = re.compile(r"(\d{1,4})(?:\.(\d{1,4}))?(?:\.(\d{1,4}))?")

#: Protocol major versions whose messages this package can decode (1 = 1.1, leniently).
SUPPORTED_MAJORS = frozenset({1, 2, 3})


def parse_version(version: str) -> tuple[int, int, int]:
    """Split ``"2.1.0"`` into ``(2, 1, 0)``; missing minor/patch count as 0.

    Raises:
        VersionError: if ``version`` is not of the form ``major[.minor[.patch]]``.
    """
    match = _VERSION_RE.fullmatch(version) if isinstance(version, str) else None
    if match is None:
        raise VersionError(f"malformed protocol version {version!r}, expected e.g. '2.1.0'")
    major, minor, patch = match.groups()
    return int(major), int(minor or 0), int(patch or 0)


# Parsed once per distinct string: these run for every message (decode, control's 3.0 checks)
# and a fleet speaks a handful of versions. The strings come from the wire, so the caches are
# bounded; malformed versions are never stored (they raise each time).
_CACHE_SIZE = 64
_MAJORS: dict[str, int] = {}
_MAJOR_LEVELS: dict[str, str] = {}


def major_of(version: str) -> int:
    """Return the major version number of ``version`` (``"2.1.0"`` → ``2``)."""
    major = _MAJORS.get(version) if type(version) is str else None
    if major is None:
        major = parse_version(version)[0]
        if type(version) is str:
            if len(_MAJORS) >= _CACHE_SIZE:
                _MAJORS.clear()
            _MAJORS[version] = major
    return major


def major_version_of(version: str) -> str:
    """Return the topic major-version level for ``version`` (``"2.1.0"`` → ``"v2"``)."""
    level = _MAJOR_LEVELS.get(version) if type(version) is str else None
    if level is None:
        level = f"v{major_of(version)}"
        if type(version) is str:
            if len(_MAJOR_LEVELS) >= _CACHE_SIZE:
                _MAJOR_LEVELS.clear()
            _MAJOR_LEVELS[version] = level
    return level


def header_version_problem(version: str | None) -> str | None:
    """What is wrong with a message header's `version`, or None: it must be
    "[Major].[Minor].[Patch]" of a supported major, or empty. A receiver keeps it as the
    vehicle's version and decodes the vehicle's next messages with it (a malformed one made
    every later message of the vehicle fail; found by fuzzing, `bench.fuzz`)."""
    if not version:
        return None
    try:
        major = major_of(version)  # cached per distinct string: a dict lookup per message
    except VersionError:
        return f"malformed version {version[:40]!r}"
    return None if major in SUPPORTED_MAJORS else f"unsupported version {version[:40]!r}"
