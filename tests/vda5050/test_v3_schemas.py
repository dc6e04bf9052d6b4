"""3.0.0 Structs and samples against the official 3.0 schemas (3.0.0-main preferred)."""

from __future__ import annotations

import json
from typing import Any

import pytest

from vda5050 import TopicKind, encode, v3

from .samples_v3 import SAMPLE3_IDS, SAMPLES3, make_connection3, make_order3
from .schema_compare import compare
from .support import KINDS_V3, V3_RELEASE_SCHEMA, V3_SCHEMA, load_schema, validator

# Modelled although a schema does not list them (documented in the Struct docstrings).
_EXTRA_FIELDS = {
    # One Action Struct serves orders and instant actions; only order actions are retriable.
    "instantActions.actions": {"retriable"},
}
# Enum members beyond a schema's enum: instant actions are NONE-only by rule, but the
# decoder accepts every blockingType so the robot can answer INVALID_INSTANT_ACTION;
# QUEUED requestStatus is named by the document (3.0 §6.9).
_ENUM_EXCEPTIONS = {
    "instantActions.actions.blockingType": {"SINGLE", "SOFT", "HARD"},
    "state.zoneRequests.requestStatus": {"QUEUED"},
    "state.edgeRequests.requestStatus": {"QUEUED"},
}


def _errors(schema: str, kind: str, message: v3.Message, *, strict: bool = False) -> list[str]:
    instance = json.loads(encode(message))
    found = validator(schema, kind, strict=strict).iter_errors(instance)
    return [f"{list(e.absolute_path)}: {e.message}" for e in found]


@pytest.mark.parametrize(("kind", "message"), SAMPLES3, ids=SAMPLE3_IDS)
@pytest.mark.parametrize("strict", [False, True], ids=["official", "strict"])
def test_sample_validates_against_3_0_main_schema(
    kind: TopicKind, message: v3.Message, strict: bool
) -> None:
    # strict = additionalProperties false everywhere: catches misspelt wire names.
    assert _errors(V3_SCHEMA, kind, message, strict=strict) == []


# The release schemas have known errors (REFERENCE §7): factsheet booleans typed string and
# a wrong required name, zoneSet property names.
_RELEASE_BROKEN = {TopicKind.FACTSHEET, TopicKind.ZONE_SET}


@pytest.mark.parametrize(
    ("kind", "message"),
    [(k, m) for k, m in SAMPLES3 if k not in _RELEASE_BROKEN],
    ids=[i for i, (k, _) in zip(SAMPLE3_IDS, SAMPLES3, strict=True) if k not in _RELEASE_BROKEN],
)
def test_sample_validates_against_3_0_release_schema(kind: TopicKind, message: v3.Message) -> None:
    assert _errors(V3_RELEASE_SCHEMA, kind, message) == []


def test_samples_cover_all_eight_topics() -> None:
    assert {kind for kind, _ in SAMPLES3} == set(TopicKind) == set(KINDS_V3)


@pytest.mark.parametrize("kind", KINDS_V3)
def test_struct_fields_match_3_0_main_schema(kind: TopicKind) -> None:
    root = load_schema(V3_SCHEMA, kind)
    problems = compare(
        v3.MESSAGE_TYPES[kind], [(root, root)], str(kind), _EXTRA_FIELDS, _ENUM_EXCEPTIONS
    )
    assert problems == []


@pytest.mark.parametrize("state", list(v3.ConnectionState))
def test_each_3_0_connection_state_validates(state: v3.ConnectionState) -> None:
    assert _errors(V3_SCHEMA, "connection", make_connection3(state)) == []


def test_3_0_schema_rejects_2_x_shapes() -> None:
    # Guards the validator: 2.x spellings must fail the 3.0 schema.
    order: dict[str, Any] = json.loads(encode(make_order3()))
    order["nodes"][0]["nodePosition"]["allowedDeviationXY"] = 0.5
    order["edges"][0]["corridor"]["corridorReferencePoint"] = "KINEMATICCENTER"
    assert len(list(validator(V3_SCHEMA, "order").iter_errors(order))) == 2
    connection = json.loads(encode(make_connection3(v3.ConnectionState.ONLINE)))
    connection["connectionState"] = "CONNECTIONBROKEN"
    assert list(validator(V3_SCHEMA, "connection").iter_errors(connection))


def test_strict_3_0_schema_rejects_2_x_field_names() -> None:
    order: dict[str, Any] = json.loads(encode(make_order3()))
    order["edges"][0]["startNodeId"] = "n1"
    order["edges"][0]["maxSpeed"] = 1.0
    assert _errors(V3_SCHEMA, "order", make_order3(), strict=True) == []
    strict = list(validator(V3_SCHEMA, "order", strict=True).iter_errors(order))
    assert len(strict) == 1  # one additionalProperties error naming both
    assert "startNodeId" in strict[0].message
