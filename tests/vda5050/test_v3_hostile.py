"""decode against hostile input for 3.0 and the lenient 1.1 path: only DecodeError escapes."""

from __future__ import annotations

import json
from collections.abc import Callable
from typing import Any

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import vda5050.codec
from vda5050 import DecodeError, TopicKind, adapt, decode, encode, v3

from .samples import make_order, make_state
from .samples_v3 import SAMPLES3, make_order3, make_state3
from .test_fuzz import json_values

_VALID = encode(make_state3())
_NESTED_ARRAYS = b"[" * 10_000 + b"]" * 10_000
_NESTED_OBJECTS = b'{"a":' * 10_000 + b"1" + b"}" * 10_000
_CHARGE = b'"stateOfCharge":76.5'

_MALFORMED = {
    "empty": b"",
    "not-json": b"hello",
    "null": b"null",
    "array": b"[]",
    "truncated": _VALID[:-1],
    "trailing-garbage": _VALID + b"x",
    "two-documents": _VALID + _VALID,
    "bom": b"\xef\xbb\xbf" + _VALID,
    "non-utf8-in-value": _VALID.replace(b'"order-42"', b'"order-\xff"'),
    "non-utf8-in-unknown-field": b'{"vendor":"\xc3\x28",' + _VALID[1:],
    "overlong-utf8": _VALID.replace(b'"order-42"', b'"\xc0\xaf"'),
    "escaped-lone-surrogate": _VALID.replace(b'"order-42"', b'"\\ud800"'),
    "utf16": _VALID.decode().encode("utf-16"),
    "deep-arrays": _NESTED_ARRAYS,
    "deep-objects": _NESTED_OBJECTS,
    "deep-arrays-in-unknown-field": b'{"vendor":' + _NESTED_ARRAYS + b"," + _VALID[1:],
    "nan": _VALID.replace(_CHARGE, b'"stateOfCharge":NaN'),
    "infinity": _VALID.replace(_CHARGE, b'"stateOfCharge":Infinity'),
    "1e400": _VALID.replace(_CHARGE, b'"stateOfCharge":1e400'),
    "nan-in-unknown-field": b'{"vendor":NaN,' + _VALID[1:],
    "comment": b"/* hi */" + _VALID,
    "trailing-comma": _VALID[:-1] + b",}",
}
_LEGACY_VALID = encode(make_state("2.0.0"))
_LEGACY_CHARGE = b'"batteryCharge":76.5'


def test_markers_were_placed() -> None:
    assert _CHARGE in _VALID
    assert b'"order-42"' in _VALID
    assert _LEGACY_CHARGE in _LEGACY_VALID


@pytest.mark.parametrize("payload", list(_MALFORMED.values()), ids=list(_MALFORMED))
def test_malformed_3_0_state_is_decode_error(payload: bytes) -> None:
    with pytest.raises(DecodeError) as info:
        decode(TopicKind.STATE, payload, version="3.0.0")
    assert info.value.kind == "state"
    assert info.value.reason


_LEGACY_MALFORMED = {
    name: payload.replace(_VALID, _LEGACY_VALID).replace(_CHARGE, _LEGACY_CHARGE)
    for name, payload in _MALFORMED.items()
}
_LEGACY_MALFORMED["nan"] = _LEGACY_VALID.replace(_LEGACY_CHARGE, b'"batteryCharge":NaN')
_LEGACY_MALFORMED["1e400"] = _LEGACY_VALID.replace(_LEGACY_CHARGE, b'"batteryCharge":1e400')


@pytest.mark.parametrize("payload", list(_LEGACY_MALFORMED.values()), ids=list(_LEGACY_MALFORMED))
def test_malformed_1_1_state_is_decode_error(payload: bytes) -> None:
    with pytest.raises(DecodeError) as info:
        decode(TopicKind.STATE, payload, version="1.1.0")
    assert info.value.kind == "state"


def _with_param_value(raw: bytes) -> bytes:
    """A valid 3.0 order whose first node action parameter value is ``raw`` JSON."""
    marker = "@@VALUE@@"
    order = make_order3()
    params = order.nodes[1].actions[0].action_parameters
    assert params is not None
    params[0] = v3.ActionParameter(key="x", value=marker)
    return encode(order).replace(f'"{marker}"'.encode(), raw)


@pytest.mark.parametrize("version", ["3.0.0", "1.1.0"])
@pytest.mark.parametrize(
    "raw",
    [b"NaN", b"Infinity", b"-Infinity", b"1e400", b"[1, -1e400]", b'{"a": 1e999}'],
    ids=["nan", "inf", "-inf", "1e400", "list", "dict"],
)
def test_non_finite_in_free_form_parameter_value_is_decode_error(raw: bytes, version: str) -> None:
    payload = _with_param_value(raw)
    if version == "1.1.0":
        legacy = encode(make_order("2.0.0"))
        payload = legacy.replace(b'"value":"floor"', b'"value":' + raw)
        assert payload != legacy
    with pytest.raises(DecodeError):
        decode(TopicKind.ORDER, payload, version=version)


@pytest.mark.parametrize("version", ["3.0.0", "1.1.0"])
def test_deep_nesting_in_parameter_value_is_decode_error(version: str) -> None:
    if version == "3.0.0":
        payload = _with_param_value(_NESTED_ARRAYS)
    else:
        payload = encode(make_order("2.0.0")).replace(
            b'"value":"floor"', b'"value":' + _NESTED_ARRAYS
        )
    with pytest.raises(DecodeError, match="nested too deeply"):
        decode(TopicKind.ORDER, payload, version=version)


def test_every_prefix_of_every_3_0_sample_is_decode_error() -> None:
    for kind, message in SAMPLES3:
        payload = encode(message)
        for cut in range(0, len(payload), 3):
            with pytest.raises(DecodeError):
                decode(kind, payload[:cut], version="3.0.0")


@pytest.mark.parametrize("version", ["3.0.0", "1.1.0"])
@pytest.mark.parametrize("payload", [None, 42, 1.5, ["a"], {"headerId": 1}])
def test_non_bytes_payload_is_decode_error(payload: Any, version: str) -> None:
    with pytest.raises(DecodeError, match="must be bytes"):
        decode(TopicKind.STATE, payload, version=version)


@pytest.mark.parametrize("version", ["3.0.0", "1.1.0"])
def test_payload_limit_applies(version: str, monkeypatch: pytest.MonkeyPatch) -> None:
    with pytest.raises(DecodeError, match="exceeds limit"):
        decode(TopicKind.STATE, b"x" * (vda5050.codec.MAX_PAYLOAD_BYTES + 1), version=version)
    payload = encode(make_state3() if version == "3.0.0" else make_state("2.0.0"))
    with pytest.raises(DecodeError, match="exceeds limit"):
        decode(TopicKind.STATE, payload, version=version, max_payload_bytes=len(payload) - 1)
    assert decode(TopicKind.STATE, payload, version=version, max_payload_bytes=len(payload))
    monkeypatch.setattr(vda5050.codec, "MAX_PAYLOAD_BYTES", 100)
    with pytest.raises(DecodeError, match="exceeds limit of 100 bytes"):
        decode(TopicKind.STATE, payload, version=version)


# --- property tests ------------------------------------------------------------------------

_SETTINGS = settings(max_examples=200, deadline=None, suppress_health_check=[HealthCheck.too_slow])
_KINDS_V3 = list(TopicKind)
_KINDS_V1 = [k for k in TopicKind if k in {"order", "instantActions", "state", "connection"}]


def _decode_or_error(kind: TopicKind, payload: bytes, version: str) -> None:
    """``decode`` either succeeds (and the result re-encodes to itself) or raises DecodeError."""
    try:
        message: Any = decode(kind, payload, version=version)
        error: DecodeError | None = None
    except DecodeError as exc:
        message, error = None, exc
    if error is not None:
        assert error.kind == kind
        assert error.reason
        return
    # Lenient 1.1 input re-encodes in 2.x shape, so decode that back as 2.0.
    again = "2.0.0" if version.startswith("1.") else version
    assert decode(kind, encode(message), version=again) == message
    # Whatever decodes can be adapted for the 2.x model (master control and simulator).
    adapter = _ADAPTERS.get(type(message))
    if adapter is not None:
        assert encode(adapter(message))


_ADAPTERS: dict[type, Callable[[Any], Any]] = {
    v3.State: adapt.state_v3_to_v2,
    v3.Factsheet: adapt.factsheet_v3_to_v2,
    v3.Visualization: adapt.visualization_v3_to_v2,
    v3.Connection: adapt.connection_v3_to_v2,
    v3.Order: adapt.order_v3_to_v2,
    v3.InstantActions: adapt.instant_actions_v3_to_v2,
}


@_SETTINGS
@given(kind=st.sampled_from(_KINDS_V3), payload=st.binary(max_size=512))
def test_random_bytes(kind: TopicKind, payload: bytes) -> None:
    _decode_or_error(kind, payload, "3.0.0")
    if kind in _KINDS_V1:
        _decode_or_error(kind, payload, "1.1.0")


@_SETTINGS
@given(kind=st.sampled_from(_KINDS_V3), value=json_values)
def test_random_json(kind: TopicKind, value: Any) -> None:
    payload = json.dumps(value).encode()
    _decode_or_error(kind, payload, "3.0.0")
    if kind in _KINDS_V1:
        _decode_or_error(kind, payload, "1.1.0")


def _paths(value: Any, prefix: tuple[Any, ...] = ()) -> list[tuple[Any, ...]]:
    found = [prefix]
    if isinstance(value, dict):
        for key, item in value.items():
            found += _paths(item, (*prefix, key))
    elif isinstance(value, list):
        for index, item in enumerate(value):
            found += _paths(item, (*prefix, index))
    return found


@_SETTINGS
@given(
    index=st.integers(min_value=0, max_value=len(SAMPLES3) - 1),
    data=st.data(),
    new=json_values,
    delete=st.booleans(),
)
def test_mutated_valid_3_0_messages(
    index: int, data: st.DataObject, new: Any, delete: bool
) -> None:
    kind, message = SAMPLES3[index]
    document = json.loads(encode(message))
    path = data.draw(st.sampled_from(_paths(document)))
    if not path:
        document = new
    else:
        parent = document
        for step in path[:-1]:
            parent = parent[step]
        if delete:
            del parent[path[-1]]
        else:
            parent[path[-1]] = new
    _decode_or_error(kind, json.dumps(document).encode(), "3.0.0")


@_SETTINGS
@given(index=st.integers(min_value=0, max_value=len(SAMPLES3) - 1), data=st.data())
def test_byte_level_corruption(index: int, data: st.DataObject) -> None:
    kind, message = SAMPLES3[index]
    payload = bytearray(encode(message))
    for _ in range(data.draw(st.integers(min_value=1, max_value=4))):
        position = data.draw(st.integers(min_value=0, max_value=len(payload) - 1))
        payload[position] = data.draw(st.integers(min_value=0, max_value=255))
    _decode_or_error(kind, bytes(payload), "3.0.0")
