"""JSON encoding and decoding of VDA 5050 messages (1.1 leniently, 2.0, 2.1, 3.0).

``decode`` is the trust boundary for everything arriving over MQTT: whatever the payload,
it returns a typed Struct or raises :class:`~vda5050.errors.DecodeError`, never anything
else, so one bad vehicle cannot crash a subscriber loop. The ``version`` selects the Struct
set: 2.x → :mod:`vda5050.v2`, 3.x → :mod:`vda5050.v3`, 1.x → the 2.x Structs after
:func:`vda5050.lenient.normalise_v1` (lower-case enums, ``informations``).

NaN/Infinity: msgspec's JSON parser already rejects the ``NaN``/``Infinity`` tokens and
numbers that overflow a float (``1e400`` → "Number out of range"), so decoded messages
never hold non-finite floats. Encoding is the weak side: msgspec silently writes NaN and
Infinity as ``null``, so :func:`encode` checks for them first and refuses.
"""

from __future__ import annotations

import math
import re
from collections.abc import Callable
from typing import Any, Literal, overload

import msgspec

from vda5050 import v3
from vda5050.enums import TopicKind
from vda5050.errors import DecodeError, EncodeError, TopicError, VersionError
from vda5050.lenient import normalise_v1
from vda5050.topics import kinds_of, parse_kind
from vda5050.v2 import (
    MESSAGE_TYPES,
    Connection,
    Factsheet,
    InstantActions,
    Message,
    Order,
    State,
    Visualization,
)
from vda5050.versions import SUPPORTED_MAJORS, header_version_problem, major_of

__all__ = ["MAX_PAYLOAD_BYTES", "AnyMessage", "Payload", "decode", "encode"]

#: A top-level message of any supported version (what :func:`decode` may return).
AnyMessage = Message | v3.Message

#: Largest payload :func:`decode` accepts, checked before parsing (memory/CPU bound for
#: hostile input). Read at call time, so tests and deployments may change it.
MAX_PAYLOAD_BYTES = 1024 * 1024

#: What :func:`decode` accepts; paho-mqtt hands out ``bytes``.
Payload = bytes | bytearray | memoryview | str

_DECODERS: dict[TopicKind, msgspec.json.Decoder[Any]] = {
    kind: msgspec.json.Decoder(type_) for kind, type_ in MESSAGE_TYPES.items()
}
_DECODERS_V3: dict[TopicKind, msgspec.json.Decoder[Any]] = {
    kind: msgspec.json.Decoder(type_) for kind, type_ in v3.MESSAGE_TYPES.items()
}
_UNTYPED = msgspec.json.Decoder()
_ENCODER = msgspec.json.Encoder()

# msgspec validation messages end with " - at `$.nodes[2].nodeId`" when tied to an element.
_PATH_RE = re.compile(r"^(?P<reason>.*) - at `(?P<path>\$[^`]*)`$", re.DOTALL)


def encode(message: msgspec.Struct) -> bytes:
    """Encode a message (or any of its parts) to compact UTF-8 JSON.

    Raises:
        EncodeError: if a float is NaN or infinite (JSON cannot represent it and msgspec
            would silently write ``null``), or the value is otherwise not encodable.
    """
    try:
        data = _ENCODER.encode(message)
    except (msgspec.EncodeError, TypeError, ValueError, OverflowError) as exc:
        # UnicodeEncodeError (lone surrogates in a str) is a ValueError subclass.
        _reject_non_finite(message)
        raise EncodeError(str(exc)) from exc
    except RecursionError:
        # Free-form parameter values nested ~1000 deep exceed msgspec's recursion budget.
        _reject_non_finite(message)
        raise EncodeError("value nested too deeply") from None
    # msgspec writes NaN and Infinity as `null`, so only output with a null can hide one: walking
    # every message's tree was a fifth of a 1,000-vehicle simulator's CPU.
    if b"null" in data:
        _reject_non_finite(message)
    return data


# The 3.0 overloads come first: a literal "3.0.0" selects the v3 Struct. mypy calls them
# unsafe because a plain ``str`` version could also be "3.0.0" at runtime; such calls get
# the 2.x type from the overloads below, which is right for every 2.x version.
@overload
def decode(  # type: ignore[overload-overlap]
    kind: Literal[TopicKind.ORDER],
    payload: Payload,
    *,
    version: Literal["3.0.0"],
    max_payload_bytes: int | None = ...,
) -> v3.Order: ...
@overload
def decode(  # type: ignore[overload-overlap]
    kind: Literal[TopicKind.INSTANT_ACTIONS],
    payload: Payload,
    *,
    version: Literal["3.0.0"],
    max_payload_bytes: int | None = ...,
) -> v3.InstantActions: ...
@overload
def decode(  # type: ignore[overload-overlap]
    kind: Literal[TopicKind.STATE],
    payload: Payload,
    *,
    version: Literal["3.0.0"],
    max_payload_bytes: int | None = ...,
) -> v3.State: ...
@overload
def decode(  # type: ignore[overload-overlap]
    kind: Literal[TopicKind.VISUALIZATION],
    payload: Payload,
    *,
    version: Literal["3.0.0"],
    max_payload_bytes: int | None = ...,
) -> v3.Visualization: ...
@overload
def decode(  # type: ignore[overload-overlap]
    kind: Literal[TopicKind.CONNECTION],
    payload: Payload,
    *,
    version: Literal["3.0.0"],
    max_payload_bytes: int | None = ...,
) -> v3.Connection: ...
@overload
def decode(  # type: ignore[overload-overlap]
    kind: Literal[TopicKind.FACTSHEET],
    payload: Payload,
    *,
    version: Literal["3.0.0"],
    max_payload_bytes: int | None = ...,
) -> v3.Factsheet: ...
@overload
def decode(
    kind: Literal[TopicKind.ZONE_SET],
    payload: Payload,
    *,
    version: Literal["3.0.0"],
    max_payload_bytes: int | None = ...,
) -> v3.ZoneSet: ...
@overload
def decode(
    kind: Literal[TopicKind.RESPONSES],
    payload: Payload,
    *,
    version: Literal["3.0.0"],
    max_payload_bytes: int | None = ...,
) -> v3.Responses: ...
@overload
def decode(
    kind: Literal[TopicKind.ORDER],
    payload: Payload,
    *,
    version: str = ...,
    max_payload_bytes: int | None = ...,
) -> Order: ...
@overload
def decode(
    kind: Literal[TopicKind.INSTANT_ACTIONS],
    payload: Payload,
    *,
    version: str = ...,
    max_payload_bytes: int | None = ...,
) -> InstantActions: ...
@overload
def decode(
    kind: Literal[TopicKind.STATE],
    payload: Payload,
    *,
    version: str = ...,
    max_payload_bytes: int | None = ...,
) -> State: ...
@overload
def decode(
    kind: Literal[TopicKind.VISUALIZATION],
    payload: Payload,
    *,
    version: str = ...,
    max_payload_bytes: int | None = ...,
) -> Visualization: ...
@overload
def decode(
    kind: Literal[TopicKind.CONNECTION],
    payload: Payload,
    *,
    version: str = ...,
    max_payload_bytes: int | None = ...,
) -> Connection: ...
@overload
def decode(
    kind: Literal[TopicKind.FACTSHEET],
    payload: Payload,
    *,
    version: str = ...,
    max_payload_bytes: int | None = ...,
) -> Factsheet: ...
@overload
def decode(
    kind: TopicKind | str,
    payload: Payload,
    *,
    version: str = ...,
    max_payload_bytes: int | None = ...,
) -> AnyMessage: ...


def decode(
    kind: TopicKind | str,
    payload: Payload,
    *,
    version: str = "2.0.0",
    max_payload_bytes: int | None = None,
) -> AnyMessage:
    """Decode ``payload`` as a message of topic ``kind``.

    Args:
        kind: topic kind (``TopicKind.STATE`` or ``"state"``); selects the Struct type.
        payload: raw MQTT payload (UTF-8 JSON).
        version: protocol version the vehicle speaks. 2.x (2.0.0 and 2.1.0 share one
            Struct set) returns :mod:`vda5050.v2` Structs, 3.x the :mod:`vda5050.v3`
            Structs of all eight topics, 1.x (no factsheet) the 2.x Structs after
            upper-casing known enum values. Unknown fields are ignored.
        max_payload_bytes: size limit, default :data:`MAX_PAYLOAD_BYTES`.

    Raises:
        DecodeError: for any problem: unknown kind (or one the version does not have) or
            unsupported version, oversized, non-UTF-8, malformed or too deeply nested JSON,
            NaN/Infinity/overflowing numbers, wrong types, missing required fields or
            out-of-range values.
    """
    # Hot path (every state and visualization of the fleet): a (kind, version) pair is checked
    # once, and an ASCII payload needs no UTF-8 decoding to be known valid.
    try:
        topic_kind, decoder = _PLANS[(kind, version)]
    except (KeyError, TypeError):  # a new pair, or an unhashable kind that _plan rejects
        topic_kind, decoder = _plan(kind, version)
    limit = MAX_PAYLOAD_BYTES if max_payload_bytes is None else max_payload_bytes
    if type(payload) is bytes and len(payload) <= limit and payload.isascii():
        data: bytes | memoryview = payload
    else:
        data = _checked_bytes(topic_kind, payload, max_payload_bytes)
    if decoder is None:
        legacy: Message = _guarded(topic_kind, lambda: _decode_v1(topic_kind, data))
        if problem := header_version_problem(legacy.version):
            raise DecodeError(topic_kind, problem, "$.version")
        return legacy
    try:
        result: AnyMessage = decoder.decode(data)
    except Exception as exc:  # incl. RecursionError; see _decode_error
        raise _decode_error(topic_kind, exc) from None
    if problem := header_version_problem(result.version):
        raise DecodeError(topic_kind, problem, "$.version")  # kept as the vehicle's version
    return result


# (kind, version) -> (kind, decoder; None for 1.x) for pairs `decode` checked. Versions come
# from the wire, so it is bounded.
_PLANS: dict[tuple[object, object], tuple[TopicKind, msgspec.json.Decoder[Any] | None]] = {}
_PLANS_SIZE = 256


def _plan(kind: object, version: str) -> tuple[TopicKind, msgspec.json.Decoder[Any] | None]:
    """Check `kind` and `version` (raising :class:`DecodeError`) and remember the pair."""
    topic_kind = _kind_or_error(kind)
    major = _major_or_error(topic_kind, version)
    if topic_kind not in kinds_of(major) or (major == 1 and topic_kind is TopicKind.FACTSHEET):
        raise DecodeError(topic_kind, f"unknown topic kind for protocol version {version!r}")
    decoders = _DECODERS_V3 if major >= 3 else _DECODERS
    plan = (topic_kind, None if major == 1 else decoders[topic_kind])
    if isinstance(kind, str) and type(version) is str:
        if len(_PLANS) >= _PLANS_SIZE:
            _PLANS.clear()  # made-up versions must not grow it without bound
        _PLANS[(kind, version)] = plan
    return plan


def _decode_v1(kind: TopicKind, data: bytes | memoryview) -> Message:
    """1.1: parse untyped, normalise to the 2.x shape, convert into the 2.x Struct."""
    document = normalise_v1(kind, _UNTYPED.decode(data))
    result: Message = msgspec.convert(document, MESSAGE_TYPES[kind])
    return result


def _guarded(kind: TopicKind, run: Callable[[], Any]) -> Any:
    """Run a msgspec decode/convert and turn every failure into :class:`DecodeError`."""
    try:
        return run()
    except Exception as exc:
        raise _decode_error(kind, exc) from None


def _decode_error(kind: TopicKind, exc: Exception) -> DecodeError:
    """The :class:`DecodeError` for a failure of msgspec's decode or convert."""
    if isinstance(exc, msgspec.ValidationError):
        match = _PATH_RE.match(str(exc))
        if match is None:
            return DecodeError(kind, str(exc))
        return DecodeError(kind, match["reason"], match["path"])
    if isinstance(exc, msgspec.DecodeError):
        # msgspec's own wording is already specific ("JSON is malformed: invalid character
        # (byte 5)", "Input data was truncated").
        return DecodeError(kind, str(exc))
    if isinstance(exc, RecursionError):
        # msgspec recurses per nesting level; ~1000 levels exhaust the interpreter limit.
        return DecodeError(kind, "JSON nested too deeply")
    # Last line of the trust boundary: no input may crash the caller with an exception type
    # it does not expect (the specific cases above cover all we know).
    return DecodeError(kind, f"{type(exc).__name__}: {exc}")


def _kind_or_error(kind: object) -> TopicKind:
    """Return ``kind`` as :class:`TopicKind` (of any version) or raise :class:`DecodeError`."""
    try:
        return parse_kind(kind, None)
    except TopicError:
        raise DecodeError(str(kind), "unknown topic kind") from None


def _major_or_error(kind: TopicKind, version: str) -> int:
    """The major version of ``version``, or :class:`DecodeError` if it is not supported."""
    try:
        major = major_of(version)
    except VersionError as exc:
        raise DecodeError(kind, str(exc)) from None
    if major not in SUPPORTED_MAJORS:
        raise DecodeError(kind, f"unsupported protocol version {version!r}")
    return major


def _checked_bytes(kind: TopicKind, payload: object, limit: int | None) -> bytes | memoryview:
    """Return ``payload`` as bytes after the size and UTF-8 checks."""
    max_bytes = MAX_PAYLOAD_BYTES if limit is None else limit
    if isinstance(payload, str):
        # A character is at least one byte: reject huge strings before encoding them.
        if len(payload) > max_bytes:
            raise DecodeError(kind, f"payload larger than {max_bytes} bytes")
        try:
            payload = payload.encode("utf-8")
        except UnicodeEncodeError as exc:
            raise DecodeError(kind, f"payload is not valid UTF-8: {exc.reason}") from None
    if not isinstance(payload, bytes | bytearray | memoryview):
        raise DecodeError(kind, f"payload must be bytes, got {type(payload).__name__}")
    size = payload.nbytes if isinstance(payload, memoryview) else len(payload)
    if size > max_bytes:
        raise DecodeError(kind, f"payload of {size} bytes exceeds limit of {max_bytes} bytes")
    try:
        # msgspec only validates UTF-8 in strings it keeps (and raises UnicodeDecodeError
        # there, not its own error); skipped unknown fields are not checked at all.
        # Validating up front rejects every non-UTF-8 payload uniformly.
        str(payload, "utf-8")
    except UnicodeDecodeError as exc:
        raise DecodeError(
            kind, f"payload is not valid UTF-8 (byte {exc.start}: {exc.reason})"
        ) from None
    except (TypeError, ValueError) as exc:  # non-contiguous memoryview and the like
        raise DecodeError(kind, f"unreadable payload: {exc}") from None
    return payload if isinstance(payload, bytes | memoryview) else bytes(payload)


_FieldNames = tuple[tuple[str, str], ...]
_FIELD_CACHE: dict[type, _FieldNames] = {}


def _struct_fields(cls: type[msgspec.Struct]) -> _FieldNames:
    """(attribute name, wire name) pairs of a Struct type, cached."""
    names = _FIELD_CACHE.get(cls)
    if names is None:
        names = tuple((f.name, f.encode_name) for f in msgspec.structs.fields(cls))
        _FIELD_CACHE[cls] = names
    return names


def _reject_non_finite(root: object) -> None:
    """Raise EncodeError with the JSON path of a NaN/Infinity float in ``root``, if any.

    Iterative on purpose: action parameter values are arbitrary JSON and could be nested
    deeper than the recursion limit.
    """
    stack: list[tuple[object, str]] = [(root, "$")]
    while stack:
        value, path = stack.pop()
        if isinstance(value, float):
            if not math.isfinite(value):
                raise EncodeError("NaN and Infinity are not allowed in VDA 5050 JSON", path)
        elif isinstance(value, msgspec.Struct):
            for attr, wire in _struct_fields(type(value)):
                stack.append((getattr(value, attr), f"{path}.{wire}"))
        elif isinstance(value, list | tuple):
            stack.extend((item, f"{path}[{i}]") for i, item in enumerate(value))
        elif isinstance(value, dict):
            stack.extend((item, f"{path}.{key}") for key, item in value.items())
