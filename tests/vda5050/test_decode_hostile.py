"""decode against hostile input: malformed, truncated, oversized, deep, non-finite."""

from __future__ import annotations

import json
from typing import Any

import msgspec
import pytest

import vda5050.codec
from vda5050 import (
    MAX_PAYLOAD_BYTES,
    ActionParameter,
    DecodeError,
    Message,
    TopicKind,
    decode,
    encode,
)

from .samples import ALL_SAMPLES, make_order, make_state


def _wire(message: Message) -> dict[str, Any]:
    result: dict[str, Any] = json.loads(encode(message))
    return result


def _bytes(value: Any) -> bytes:
    return json.dumps(value).encode()


# --- hostile input ------------------------------------------------------------------------

_VALID_STATE = encode(make_state("2.0.0"))
_NESTED_ARRAYS = b"[" * 10_000 + b"]" * 10_000
_NESTED_OBJECTS = b'{"a":' * 10_000 + b"1" + b"}" * 10_000


def _with_param_value(raw: bytes) -> bytes:
    """An otherwise valid order whose first action parameter value is ``raw`` JSON."""
    marker = "@@VALUE@@"
    order = make_order("2.0.0")
    action = order.nodes[1].actions[0]
    assert action.action_parameters is not None
    action.action_parameters[0] = ActionParameter(key="x", value=marker)
    return encode(order).replace(f'"{marker}"'.encode(), raw)


_MALFORMED = {
    "empty": b"",
    "whitespace": b"   ",
    "not-json": b"hello",
    "null": b"null",
    "array": b"[]",
    "number": b"42",
    "truncated": _VALID_STATE[:-1],
    "truncated-half": _VALID_STATE[: len(_VALID_STATE) // 2],
    "trailing-garbage": _VALID_STATE + b"x",
    "two-documents": _VALID_STATE + _VALID_STATE,
    "nul-byte": b"\x00",
    "bom": b"\xef\xbb\xbf" + _VALID_STATE,
    "non-utf8-in-value": _VALID_STATE.replace(b'"order-42"', b'"order-\xff"'),
    "non-utf8-in-unknown-field": b'{"vendor":"\xc3\x28",' + _VALID_STATE[1:],
    "overlong-utf8": _VALID_STATE.replace(b'"order-42"', b'"\xc0\xaf"'),
    "utf8-encoded-surrogate": _VALID_STATE.replace(b'"order-42"', b'"\xed\xa0\x80"'),
    "escaped-lone-surrogate": _VALID_STATE.replace(b'"order-42"', b'"\\ud800"'),
    "latin1": '{"orderId": "Bühne"}'.encode("latin-1"),
    "utf16": _VALID_STATE.decode().encode("utf-16"),
    "deep-arrays": _NESTED_ARRAYS,
    "deep-objects": _NESTED_OBJECTS,
    "deep-arrays-in-unknown-field": b'{"vendor":' + _NESTED_ARRAYS + b"," + _VALID_STATE[1:],
    "nan": _VALID_STATE.replace(b'"batteryCharge":76.5', b'"batteryCharge":NaN'),
    "infinity": _VALID_STATE.replace(b'"batteryCharge":76.5', b'"batteryCharge":Infinity'),
    "-infinity": _VALID_STATE.replace(b'"batteryCharge":76.5', b'"batteryCharge":-Infinity'),
    "1e400": _VALID_STATE.replace(b'"batteryCharge":76.5', b'"batteryCharge":1e400'),
    "-1e400": _VALID_STATE.replace(b'"batteryCharge":76.5', b'"batteryCharge":-1e400'),
    "nan-in-unknown-field": b'{"vendor":NaN,' + _VALID_STATE[1:],
    "nan-string-is-not-a-number": _VALID_STATE.replace(
        b'"batteryCharge":76.5', b'"batteryCharge":"NaN"'
    ),
    "single-quotes": b"{'headerId': 1}",
    "comment": b"/* hi */" + _VALID_STATE,
    "trailing-comma": _VALID_STATE[:-1] + b",}",
}


@pytest.mark.parametrize("payload", list(_MALFORMED.values()), ids=list(_MALFORMED))
def test_malformed_state_payload_is_decode_error(payload: bytes) -> None:
    with pytest.raises(DecodeError) as info:
        decode(TopicKind.STATE, payload)
    assert info.value.kind == "state"
    assert info.value.reason


def test_nan_infinity_markers_were_placed() -> None:
    # The replace() calls above must hit, otherwise those cases test a valid payload.
    assert b'"batteryCharge":76.5' in _VALID_STATE
    assert b'"order-42"' in _VALID_STATE


@pytest.mark.parametrize(
    "raw",
    [b"NaN", b"Infinity", b"-Infinity", b"1e400", b"[1, -1e400]", b'{"a": 1e999}'],
    ids=["nan", "inf", "-inf", "1e400", "list", "dict"],
)
def test_non_finite_in_free_form_parameter_value_is_decode_error(raw: bytes) -> None:
    with pytest.raises(DecodeError):
        decode(TopicKind.ORDER, _with_param_value(raw))


def test_free_form_parameter_value_holds_valid_json() -> None:
    order = decode(TopicKind.ORDER, _with_param_value(b'{"a": [1, 1e300, -0.0]}'))
    action = order.nodes[1].actions[0]
    assert action.action_parameters is not None
    assert action.action_parameters[0].value == {"a": [1, 1e300, -0.0]}


def test_deep_nesting_in_parameter_value_is_decode_error() -> None:
    with pytest.raises(DecodeError, match="nested too deeply"):
        decode(TopicKind.ORDER, _with_param_value(_NESTED_ARRAYS))


def test_moderate_nesting_in_parameter_value_is_fine() -> None:
    order = decode(TopicKind.ORDER, _with_param_value(b"[" * 50 + b"]" * 50))
    assert order.order_id == "order-42"


@pytest.mark.parametrize("cut", range(1, 400, 7))
def test_every_truncation_is_decode_error(cut: int) -> None:
    payload = encode(make_order("2.1.0"))
    with pytest.raises(DecodeError):
        decode(TopicKind.ORDER, payload[:cut])


def test_every_prefix_of_every_sample_is_decode_error() -> None:
    for version, kind, message in ALL_SAMPLES:
        payload = encode(message)
        for cut in range(len(payload)):
            with pytest.raises(DecodeError):
                decode(kind, payload[:cut], version=version)


@pytest.mark.parametrize("payload", [None, 42, 1.5, ["a"], {"headerId": 1}])
def test_non_bytes_payload_is_decode_error(payload: Any) -> None:
    with pytest.raises(DecodeError, match="must be bytes"):
        decode(TopicKind.STATE, payload)


def test_payload_limit_is_checked_before_parsing() -> None:
    # Not JSON at all: only a size check that runs first can produce the size message.
    oversized = b"x" * (MAX_PAYLOAD_BYTES + 1)
    with pytest.raises(DecodeError, match="exceeds limit"):
        decode(TopicKind.STATE, oversized)
    with pytest.raises(DecodeError, match="larger than"):
        decode(TopicKind.STATE, "x" * (MAX_PAYLOAD_BYTES + 1))


def test_payload_exactly_at_limit_is_parsed() -> None:
    payload = encode(make_state("2.0.0"))
    padded = payload[:-1] + b" " * (MAX_PAYLOAD_BYTES - len(payload)) + b"}"
    assert len(padded) == MAX_PAYLOAD_BYTES
    assert decode(TopicKind.STATE, padded) == make_state("2.0.0")


def test_payload_limit_is_configurable(monkeypatch: pytest.MonkeyPatch) -> None:
    payload = encode(make_state("2.0.0"))
    with pytest.raises(DecodeError, match="exceeds limit"):
        decode(TopicKind.STATE, payload, max_payload_bytes=len(payload) - 1)
    assert decode(TopicKind.STATE, payload, max_payload_bytes=len(payload))
    monkeypatch.setattr(vda5050.codec, "MAX_PAYLOAD_BYTES", 100)
    with pytest.raises(DecodeError, match="exceeds limit of 100 bytes"):
        decode(TopicKind.STATE, payload)


def test_msgspec_itself_rejects_non_finite_numbers() -> None:
    # The codec relies on this instead of walking decoded messages (see codec docstring);
    # if a msgspec upgrade changes it, this test says so.
    for raw in (b"NaN", b"Infinity", b"-Infinity", b"1e400", b"-1e400"):
        with pytest.raises(msgspec.DecodeError):
            msgspec.json.decode(raw, type=float)


@pytest.mark.parametrize(
    ("version", "reason"),
    [
        ("ac2.0.1", "malformed version"),  # what the fuzzer sent (bench.fuzz)
        ("2.x", "malformed version"),
        ("9.0.0", "unsupported version"),
    ],
)
@pytest.mark.parametrize("kind", [TopicKind.STATE, TopicKind.CONNECTION, TopicKind.FACTSHEET])
def test_a_header_version_that_is_malformed_or_unsupported_is_refused(
    kind: TopicKind, version: str, reason: str
) -> None:
    valid = next(m for v, k, m in ALL_SAMPLES if k == kind and v == "2.0.0")
    wire = _wire(valid) | {"version": version}
    with pytest.raises(DecodeError) as refused:
        decode(kind, _bytes(wire))
    assert refused.value.path == "$.version"
    assert reason in refused.value.reason


@pytest.mark.parametrize("version", ["2.1.0", "2.1", "1.1.0", ""])
def test_a_well_formed_or_empty_header_version_is_kept(version: str) -> None:
    state = decode(TopicKind.STATE, _bytes(_wire(make_state("2.0.0")) | {"version": version}))
    assert state.version == version
