"""Topic parsing, building and validation."""

from __future__ import annotations

import pytest

from vda5050 import (
    Topic,
    TopicError,
    TopicKind,
    VDA5050Error,
    VersionError,
    major_version_of,
    subscription,
)
from vda5050.topics import kinds_of

_CASES = [("v2", kind) for kind in kinds_of(2)] + [("v3", kind) for kind in TopicKind]


@pytest.mark.parametrize(("major", "kind"), _CASES, ids=[f"{m}-{k}" for m, k in _CASES])
def test_parse_and_build_round_trip(major: str, kind: TopicKind) -> None:
    text = f"uagv/{major}/Acme/AGV-001/{kind}"
    topic = Topic.parse(text)
    assert topic == Topic(
        interface_name="uagv",
        major_version=major,
        manufacturer="Acme",
        serial_number="AGV-001",
        kind=kind,
    )
    assert topic.kind is kind
    assert topic.build() == text
    assert str(topic) == text


def test_topic_kind_wire_spelling() -> None:
    assert [str(k) for k in TopicKind] == [
        "order",
        "instantActions",
        "state",
        "visualization",
        "connection",
        "factsheet",
        "zoneSet",
        "responses",
    ]


def test_kind_given_as_string_is_normalised() -> None:
    topic = Topic("uagv", "v2", "Acme", "AGV-001", "state")  # type: ignore[arg-type]
    assert topic.kind is TopicKind.STATE


def test_with_kind_and_hashing() -> None:
    state = Topic.parse("uagv/v2/Acme/AGV-001/state")
    order = state.with_kind(TopicKind.ORDER)
    assert str(order) == "uagv/v2/Acme/AGV-001/order"
    assert state.kind is TopicKind.STATE  # frozen: the original is unchanged
    assert {state, Topic.parse("uagv/v2/Acme/AGV-001/state")} == {state}
    with pytest.raises(AttributeError):
        state.serial_number = "other"  # type: ignore[misc]


def test_serial_number_may_use_all_allowed_characters() -> None:
    topic = Topic.parse("uagv/v2/Acme Robotics GmbH/aZ09_.:-/state")
    assert topic.serial_number == "aZ09_.:-"
    assert topic.manufacturer == "Acme Robotics GmbH"


@pytest.mark.parametrize(
    "text",
    [
        "",
        "uagv/v2/Acme/AGV-001",  # four levels
        "uagv/v2/Acme/AGV-001/state/extra",  # six levels
        "/uagv/v2/Acme/AGV-001/state",
        "uagv/v2/Acme/AGV-001/state/",
        "uagv//Acme/AGV-001/state",  # empty level
        "uagv/v2//AGV-001/state",
        "uagv/v2/Acme//state",
        "/v2/Acme/AGV-001/state",
        "uagv/v2/+/AGV-001/state",  # wildcards
        "uagv/v2/Acme/#/state",
        "uagv/v2/Acme/AGV-001/#",
        "uagv/v2/Ac+me/AGV-001/state",
        "$SYS/v2/Acme/AGV-001/state",  # broker-internal prefix
        "uagv/v$2/Acme/AGV-001/state",
        "uagv/v2/Acme/AGV\x00001/state",
        "uagv/v2/Acme/AGV 001/state",  # serial outside A-Za-z0-9_.:-
        "uagv/v2/Acme/AGV@001/state",
        "uagv/v2/Acme/AGV-ü/state",
        "uagv/v2/Acme/AGV,001/state",
        "uagv/v2/Acme/AGV-001/zoneSet",  # 3.0 topic, unknown in 2.x
        "uagv/v2/Acme/AGV-001/State",  # topic names are case-sensitive
        "uagv/v2/Acme/AGV-001/instantactions",
        "uagv/v2/Acme/AGV-001/",
    ],
)
def test_parse_rejects(text: str) -> None:
    with pytest.raises(TopicError):
        Topic.parse(text)


def test_topic_error_is_package_error() -> None:
    with pytest.raises(VDA5050Error):
        Topic.parse("nope")


@pytest.mark.parametrize(
    "levels",
    [
        ("", "v2", "Acme", "AGV-001", "state"),
        ("uagv", "v2/x", "Acme", "AGV-001", "state"),
        ("uagv", "v2", "Ac#me", "AGV-001", "state"),
        ("uagv", "v2", "Acme", "AGV 001", "state"),
        ("uagv", "v2", "Acme", "AGV-001", "responses"),
        ("uagv", "v2", "Acme", 17, "state"),
    ],
)
def test_constructor_validates(levels: tuple[object, ...]) -> None:
    with pytest.raises(TopicError):
        Topic(*levels)  # type: ignore[arg-type]


def test_parse_rejects_non_string() -> None:
    with pytest.raises(TopicError):
        Topic.parse(b"uagv/v2/Acme/AGV-001/state")  # type: ignore[arg-type]


def test_subscription() -> None:
    assert subscription("uagv") == "uagv/v2/+/+/#"
    assert subscription("uagv", "v3") == "uagv/v3/+/+/#"
    assert subscription("fleet", kind=TopicKind.STATE) == "fleet/v2/+/+/state"
    with pytest.raises(TopicError):
        subscription("ua/gv")
    with pytest.raises(TopicError):
        subscription("")
    with pytest.raises(TopicError):
        subscription("uagv", kind="zoneSet")  # type: ignore[arg-type]


@pytest.mark.parametrize(
    ("version", "expected"),
    [("2.0.0", "v2"), ("2.1.0", "v2"), ("3.0.0", "v3"), ("1.1", "v1"), ("2", "v2")],
)
def test_major_version_of(version: str, expected: str) -> None:
    assert major_version_of(version) == expected


@pytest.mark.parametrize("version", ["", "v2", "2.x", "2.1.0-rc1", "two", " 2.1.0", "2..1"])
def test_major_version_of_rejects(version: str) -> None:
    with pytest.raises(VersionError):
        major_version_of(version)


def test_topic_for_a_version_uses_its_major() -> None:
    topic = Topic("uagv", major_version_of("2.1.0"), "Acme", "AGV-001", TopicKind.ORDER)
    assert str(topic) == "uagv/v2/Acme/AGV-001/order"
