"""REFERENCE J.44: the factsheet's string limits, checked on every message before it is sent.

`protocolLimits.maxStringLens` (3.0 `maximumStringLengths`): msgLen (the encoded message),
topicSerialLen (the serial number in the topic), topicElemLen (every topic level), idLen and
idNumericalOnly (every id we send: orderId, nodeId, edgeId, actionId, mapId), enumLen (every
enum value we send) and loadIdLen (the loadId action parameter). 0 or absent = no limit. A
message that does not fit is not sent: the order (or instant action) is refused with the
reason instead, because the vehicle would only reject it.
"""

import functools
import re
from typing import Any

import msgspec

from control.capabilities import StringLimits

_ID_KEYS = frozenset({"orderId", "nodeId", "edgeId", "actionId", "mapId"})
_ENUM_KEYS = frozenset({"blockingType", "orientationType", "corridorRefPoint"})
_CHECKED_KEYS = _ID_KEYS | _ENUM_KEYS | {"loadId"}


class ProtocolLimitError(ValueError):
    """A message breaks one of the vehicle's protocol limits; the text says which."""


def check_message(limits: StringLimits, topic: str, payload: bytes) -> None:
    """Raise ProtocolLimitError if `payload` (JSON) on `topic` breaks `limits`."""
    if limits.msg_len is not None and len(payload) > limits.msg_len:
        raise ProtocolLimitError(
            f"message of {len(payload)} bytes exceeds the vehicle's msgLen {limits.msg_len}"
        )
    levels = topic.split("/")
    if limits.topic_serial_len is not None and len(levels) >= 4:
        serial = levels[3]
        if len(serial) > limits.topic_serial_len:
            raise ProtocolLimitError(
                f"serial number {serial!r} exceeds topicSerialLen {limits.topic_serial_len}"
            )
    if limits.topic_elem_len is not None:
        for level in levels:
            if len(level) > limits.topic_elem_len:
                raise ProtocolLimitError(
                    f"topic level {level!r} exceeds topicElemLen {limits.topic_elem_len}"
                )
    # Most factsheets set no string limit; with one, a scan of the text in C tells whether
    # any string could break it, and only then is the message decoded and walked.
    if limits.limits_strings and any(scan.search(payload) for scan in _suspects(limits)):
        for key, value in _strings(msgspec.json.decode(payload)):
            _check_string(limits, key, value)


def _check_string(limits: StringLimits, key: str, value: str) -> None:
    if key in _ID_KEYS:
        if limits.id_len is not None and len(value) > limits.id_len:
            raise ProtocolLimitError(f"{key} {value!r} exceeds idLen {limits.id_len}")
        if limits.id_numerical_only and not value.isdigit():
            raise ProtocolLimitError(
                f"{key} {value!r} is not numerical; the vehicle takes numerical ids only"
            )
    elif key in _ENUM_KEYS and limits.enum_len is not None and len(value) > limits.enum_len:
        raise ProtocolLimitError(f"{key} {value!r} exceeds enumLen {limits.enum_len}")
    elif key == "loadId" and limits.load_id_len is not None and len(value) > limits.load_id_len:
        raise ProtocolLimitError(f"loadId {value!r} exceeds loadIdLen {limits.load_id_len}")


def _strings(node: Any, key: str = "") -> list[tuple[str, str]]:
    """(key, value) of every string in a decoded message that a limit applies to (ids, enums,
    loadId), in document order; action parameters under their key.

    Iterative, and keeping only what `_check_string` looks at: a long order with its horizon
    is checked on every update, and the recursive walk that listed every string was a tenth of
    control's message handling (issue 11)."""
    found: list[tuple[str, str]] = []
    stack: list[tuple[str, Any]] = [(key, node)]
    while stack:
        key, node = stack.pop()
        kind = type(node)
        if kind is str:
            if key in _CHECKED_KEYS:
                found.append((key, node))
        elif kind is dict:
            if len(node) == 2 and isinstance(node.get("key"), str) and "value" in node:
                stack.append((node["key"], node["value"]))  # an action parameter
            else:
                stack.extend(reversed(node.items()))
        elif kind is list:
            stack.extend((key, child) for child in reversed(node))
    return found


@functools.cache
def _suspects(limits: StringLimits) -> tuple[re.Pattern[bytes], ...]:
    """Scans of the JSON text that find every string that could break `limits`, and more.

    Walking a long order with its horizon, on every update, was most of publishing it
    (issue 11); these scans, each starting with a literal that `re` searches for quickly, let
    the walk run only when it may find something. Every limited key ends in `Id`, `Type` or
    `RefPoint`, and a JSON string cannot hold an unescaped quote, so `Id"` followed by a
    colon is the end of a key. A value is suspect when it is a list (its strings count under
    the key) or an object, a string longer than a limit in bytes (never fewer than its
    characters) or holding an escape, or with `idNumericalOnly` not all ASCII digits; so is
    any whitespace around the colon. An action parameter with a limited key is suspect on the
    same terms, or when its key does not come first.
    """
    lengths = [n for n in (limits.id_len, limits.load_id_len, limits.enum_len) if n is not None]
    ids = [n for n in (limits.id_len, limits.load_id_len) if n is not None]
    numeric = limits.id_numerical_only

    def value(limit: int | None, numeric: bool) -> bytes:
        forms = [rb"[\s\[{]"]
        if limit is not None:  # up to `limit` plain bytes, possessively, then no quote:
            # more bytes than `limit`, or a backslash
            forms.append(rb'"[^"\\]{0,%d}+[^"]' % limit)
        if numeric:
            forms.append(rb'"(?![0-9]+")')
        return b"(?:" + b"|".join(forms) + b")"

    scans = []
    if ids or numeric:
        scans.append(b'Id"(?:\\s|:' + value(min(ids, default=None), numeric) + b")")
    if limits.enum_len is not None:
        enum = b'"(?:\\s|:' + value(limits.enum_len, False) + b")"
        scans += [b"Type" + enum, b"RefPoint" + enum]
    keys = b"|".join(sorted(key.encode() for key in _CHECKED_KEYS))
    parameter = rb'"key"\s*:\s*"(?:' + keys + rb')"\s*(?:\}|,\s*"value"\s*:\s*'
    scans.append(parameter + value(min(lengths, default=None), numeric) + b")")
    return tuple(re.compile(scan) for scan in scans)
