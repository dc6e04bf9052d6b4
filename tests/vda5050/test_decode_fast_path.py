"""`decode` remembers (kind, version) pairs and skips UTF-8 decoding for ASCII payloads: the
shortcut must accept and reject exactly what the full checks do."""

import contextlib

import pytest

import vda5050
from vda5050 import DecodeError, TopicKind, codec, versions

VISUALIZATION = b'{"headerId":1,"manufacturer":"m\xc3\xbcller","serialNumber":"AGV-1"}'


def test_a_remembered_pair_still_rejects_invalid_utf8_in_any_part_of_the_payload() -> None:
    vda5050.decode(TopicKind.VISUALIZATION, b'{"headerId":1}')  # remembered now
    bad = b'{"headerId":1,"unknownField":"\xff\xfe"}'  # msgspec alone skips unknown fields

    with pytest.raises(DecodeError, match="not valid UTF-8"):
        vda5050.decode(TopicKind.VISUALIZATION, bad)
    with pytest.raises(DecodeError, match="not valid UTF-8"):
        vda5050.decode("visualization", bytearray(bad))


def test_non_ascii_utf8_is_decoded_on_the_full_path() -> None:
    for payload in (VISUALIZATION, bytearray(VISUALIZATION), memoryview(VISUALIZATION)):
        message = vda5050.decode(TopicKind.VISUALIZATION, payload)
        assert message.manufacturer == "müller"


def test_the_size_limit_holds_for_remembered_pairs(monkeypatch: pytest.MonkeyPatch) -> None:
    vda5050.decode(TopicKind.VISUALIZATION, b"{}")
    monkeypatch.setattr(codec, "MAX_PAYLOAD_BYTES", 10)

    with pytest.raises(DecodeError, match="exceeds limit of 10 bytes"):
        vda5050.decode(TopicKind.VISUALIZATION, b'{"headerId":1}')
    with pytest.raises(DecodeError, match="exceeds limit of 5 bytes"):
        vda5050.decode(TopicKind.VISUALIZATION, b"{}    ", max_payload_bytes=5)


def test_malformed_json_and_wrong_types_are_decode_errors_on_the_fast_path() -> None:
    vda5050.decode(TopicKind.VISUALIZATION, b"{}")

    with pytest.raises(DecodeError, match="malformed"):
        vda5050.decode(TopicKind.VISUALIZATION, b'{"headerId":}')
    with pytest.raises(DecodeError) as error:
        vda5050.decode(TopicKind.VISUALIZATION, b'{"agvPosition":{"x":"far"}}')
    assert error.value.path == "$.agvPosition.x"
    with pytest.raises(DecodeError, match="nested too deeply"):
        vda5050.decode(TopicKind.VISUALIZATION, b'{"x":' + b"[" * 5000 + b"]" * 5000 + b"}")


def test_kinds_a_version_lacks_stay_rejected_after_other_versions_were_remembered() -> None:
    for version in ("3.0.0", "2.0.0", "1.1.0"):
        with contextlib.suppress(DecodeError):  # remembered whether or not the payload fits
            vda5050.decode(TopicKind.VISUALIZATION, b"{}", version=version)

    with pytest.raises(DecodeError, match="unknown topic kind"):
        vda5050.decode(TopicKind.ZONE_SET, b"{}", version="2.0.0")
    with pytest.raises(DecodeError, match="unknown topic kind"):
        vda5050.decode(TopicKind.FACTSHEET, b"{}", version="1.1.0")


def test_made_up_versions_from_the_wire_do_not_grow_the_caches_without_bound() -> None:
    for minor in range(1000):
        vda5050.decode(TopicKind.VISUALIZATION, b"{}", version=f"2.{minor}.0")
        assert versions.major_version_of(f"2.{minor}.1") == "v2"

    assert len(codec._PLANS) <= codec._PLANS_SIZE
    assert len(versions._MAJORS) <= versions._CACHE_SIZE
    assert len(versions._MAJOR_LEVELS) <= versions._CACHE_SIZE


def test_malformed_versions_raise_every_time() -> None:
    for _ in range(2):
        with pytest.raises(vda5050.VersionError):
            versions.major_of("two")
        with pytest.raises(DecodeError, match="malformed protocol version"):
            vda5050.decode(TopicKind.STATE, b"{}", version="two")
    assert versions.major_of("3.0") == 3
    assert versions.major_version_of("3.0") == "v3"
