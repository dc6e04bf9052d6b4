"""Everything we encode validates against the official schema of its version."""

from __future__ import annotations

import json
import types

import pytest

from vda5050 import (
    MESSAGE_TYPES,
    ConnectionState,
    Message,
    TopicKind,
    encode,
)
from vda5050.v2 import VDAStruct

from .factsheet_sample import make_factsheet
from .samples import ALL_SAMPLE_IDS, ALL_SAMPLES, make_connection, make_order, make_state
from .schema_compare import compare, structs_in
from .support import KINDS, VERSIONS, load_schema, validator


def _errors(version: str, kind: str, message: Message, **options: bool) -> list[str]:
    instance = json.loads(encode(message))
    found = validator(version, kind, **options).iter_errors(instance)
    return [f"{list(e.absolute_path)}: {e.message}" for e in found]


@pytest.mark.parametrize(("version", "kind", "message"), ALL_SAMPLES, ids=ALL_SAMPLE_IDS)
def test_sample_validates_against_official_schema(
    version: str, kind: TopicKind, message: Message
) -> None:
    assert _errors(version, kind, message) == []


@pytest.mark.parametrize(("version", "kind", "message"), ALL_SAMPLES, ids=ALL_SAMPLE_IDS)
def test_sample_uses_only_properties_declared_by_its_version(
    version: str, kind: TopicKind, message: Message
) -> None:
    # additionalProperties=false everywhere: catches misspelt wire names and 2.1-only
    # fields leaking into 2.0 messages, which the permissive official schemas accept.
    assert _errors(version, kind, message, strict=True) == []


@pytest.mark.parametrize("version", VERSIONS)
def test_samples_cover_all_six_topics(version: str) -> None:
    kinds = {kind for v, kind, _ in ALL_SAMPLES if v == version}
    assert kinds == set(KINDS)


def test_strict_check_rejects_2_1_fields_in_a_2_0_message() -> None:
    # Guards the guard: a 2.1 order (corridor) must fail the strict 2.0 schema.
    order = make_order("2.1.0")
    assert _errors("2.0.0", "order", order, strict=True)
    assert _errors("2.0.0", "order", order) == []  # the official schema cannot tell


def test_unset_2_1_fields_are_not_emitted() -> None:
    wire = json.loads(encode(make_state("2.0.0")))
    assert "maps" not in wire
    assert all("errorHint" not in error for error in wire["errors"])
    order = json.loads(encode(make_order("2.0.0")))
    assert all("corridor" not in edge for edge in order["edges"])
    assert "vehicleConfig" not in json.loads(encode(make_factsheet("2.0.0")))


@pytest.mark.parametrize("version", VERSIONS)
def test_factsheet_avoiding_schema_bugs_validates_unpatched_schema(version: str) -> None:
    factsheet = make_factsheet(version, upstream_compatible=True)
    assert _errors(version, "factsheet", factsheet, patched=False) == []


@pytest.mark.parametrize("version", VERSIONS)
def test_upstream_blocking_types_bug_is_real(version: str) -> None:
    # Documents why the tests patch the schema: the upstream enum-on-array rejects any
    # non-empty blockingTypes list, however correct.
    assert _errors(version, "factsheet", make_factsheet(version), patched=False)


@pytest.mark.parametrize("version", VERSIONS)
@pytest.mark.parametrize("state", list(ConnectionState))
def test_each_connection_state_validates(version: str, state: ConnectionState) -> None:
    assert _errors(version, "connection", make_connection(version, state)) == []


def test_schema_rejects_a_broken_message() -> None:
    # Guards against a validator that accepts everything (e.g. a wrong draft).
    instance = json.loads(encode(make_order("2.0.0")))
    del instance["nodes"][0]["actions"]
    instance["edges"][0]["released"] = "yes"
    errors = list(validator("2.0.0", "order").iter_errors(instance))
    assert len(errors) == 2


# --- Struct definitions match the schemas -------------------------------------------------

# Fields we model although no schema lists them (document-only or deliberately extra).
_EXTRA_FIELDS = {
    "factsheet.physicalParameters": {"angularSpeedMin", "angularSpeedMax"},
    # AgvPosition is shared with state, whose schema has mapDescription.
    "visualization.agvPosition": {"mapDescription"},
}


@pytest.mark.parametrize("kind", KINDS)
def test_struct_fields_match_schema_properties(kind: TopicKind) -> None:
    roots = [load_schema(version, kind) for version in VERSIONS]
    schemas = [(root, root) for root in roots]
    problems = compare(MESSAGE_TYPES[kind], schemas, str(kind), _EXTRA_FIELDS)
    assert problems == []


def test_schema_comparison_detects_differences() -> None:
    # Guards the comparison itself against silently passing.
    class Broken(VDAStruct, kw_only=True):
        connection_state: str
        surplus: int

    root = load_schema("2.0.0", "connection")
    problems = compare(Broken, [(root, root)], "connection")
    assert any("lacks" in p and "headerId" in p for p in problems)
    assert any("undeclared" in p and "surplus" in p for p in problems)


def test_union_helper_sees_through_optional_lists() -> None:
    from vda5050 import Node

    assert structs_in(list[Node] | None) == [Node]
    assert structs_in(types.NoneType) == []
