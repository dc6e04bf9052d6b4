"""Property tests: whatever arrives over MQTT, ``decode`` raises DecodeError or succeeds."""

from __future__ import annotations

import json
from typing import Any

from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from vda5050 import DecodeError, Message, TopicKind, decode, encode

from .samples import samples
from .support import KINDS, VERSIONS

_SETTINGS = settings(max_examples=300, deadline=None, suppress_health_check=[HealthCheck.too_slow])

_SAMPLES: list[tuple[TopicKind, Message]] = [
    item for version in VERSIONS for item in samples(version)
]
_WIRE_KEYS = sorted(
    {key for _, message in _SAMPLES for key in json.loads(encode(message))}
    | {"nodeId", "sequenceId", "actions", "x", "y", "mapId", "actionId", "blockingType"}
)

_scalars = (
    st.none()
    | st.booleans()
    | st.integers(min_value=-(2**70), max_value=2**70)
    | st.floats()  # includes NaN and ±inf: json.dumps writes them as NaN/Infinity tokens
    | st.text(max_size=20)
    | st.sampled_from(["NONE", "ONLINE", "AUTOMATIC", "WARNING", "2.0.0", ""])
)
_keys = st.sampled_from(_WIRE_KEYS) | st.text(max_size=10)
json_values = st.recursive(
    _scalars,
    lambda children: st.lists(children, max_size=5) | st.dictionaries(_keys, children, max_size=8),
    max_leaves=30,
)


def _decode_or_decode_error(kind: TopicKind, payload: bytes, version: str = "2.0.0") -> None:
    """Assert that ``decode`` either succeeds (and re-encodes) or raises DecodeError."""
    # Any other exception type propagates and fails the test.
    try:
        message: Message | None = decode(kind, payload, version=version)
        error: DecodeError | None = None
    except DecodeError as exc:
        message, error = None, exc
    if error is not None:
        assert error.kind == kind
        assert error.reason
        return
    assert message is not None
    # Anything accepted must be usable: it encodes and decodes back to itself.
    assert decode(kind, encode(message), version=version) == message


@_SETTINGS
@given(kind=st.sampled_from(KINDS), payload=st.binary(max_size=512))
def test_random_bytes(kind: TopicKind, payload: bytes) -> None:
    _decode_or_decode_error(kind, payload)


@_SETTINGS
@given(kind=st.sampled_from(KINDS), value=json_values)
def test_random_json(kind: TopicKind, value: Any) -> None:
    _decode_or_decode_error(kind, json.dumps(value).encode())


@_SETTINGS
@given(
    kind=st.sampled_from(KINDS),
    fields=st.dictionaries(st.sampled_from(_WIRE_KEYS), json_values, max_size=12),
)
def test_random_objects_with_real_field_names(kind: TopicKind, fields: dict[str, Any]) -> None:
    _decode_or_decode_error(kind, json.dumps(fields).encode())


def _paths(value: Any, prefix: tuple[Any, ...] = ()) -> list[tuple[Any, ...]]:
    """Every path to a sub-value of a JSON document."""
    found = [prefix]
    if isinstance(value, dict):
        for key, item in value.items():
            found += _paths(item, (*prefix, key))
    elif isinstance(value, list):
        for index, item in enumerate(value):
            found += _paths(item, (*prefix, index))
    return found


def _replace(document: Any, path: tuple[Any, ...], new: Any, delete: bool) -> Any:
    if not path:
        return new
    parent = document
    for step in path[:-1]:
        parent = parent[step]
    if delete:
        del parent[path[-1]]
    else:
        parent[path[-1]] = new
    return document


@_SETTINGS
@given(
    index=st.integers(min_value=0, max_value=len(_SAMPLES) - 1),
    data=st.data(),
    new=json_values,
    delete=st.booleans(),
)
def test_mutated_valid_messages(index: int, data: st.DataObject, new: Any, delete: bool) -> None:
    kind, message = _SAMPLES[index]
    document = json.loads(encode(message))
    path = data.draw(st.sampled_from(_paths(document)))
    mutated = _replace(document, path, new, delete and bool(path))
    _decode_or_decode_error(kind, json.dumps(mutated).encode(), version="2.1.0")


@_SETTINGS
@given(
    index=st.integers(min_value=0, max_value=len(_SAMPLES) - 1),
    data=st.data(),
)
def test_byte_level_corruption(index: int, data: st.DataObject) -> None:
    kind, message = _SAMPLES[index]
    payload = bytearray(encode(message))
    for _ in range(data.draw(st.integers(min_value=1, max_value=4))):
        position = data.draw(st.integers(min_value=0, max_value=len(payload) - 1))
        payload[position] = data.draw(st.integers(min_value=0, max_value=255))
    _decode_or_decode_error(kind, bytes(payload))


@_SETTINGS
@given(kind=st.sampled_from(KINDS), depth=st.integers(min_value=1, max_value=20_000))
def test_arbitrary_nesting_depth(kind: TopicKind, depth: int) -> None:
    _decode_or_decode_error(kind, b"[" * depth + b"]" * depth)
    _decode_or_decode_error(kind, b'{"x":' * depth + b"0" + b"}" * depth)
