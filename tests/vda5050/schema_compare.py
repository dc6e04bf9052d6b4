"""Compare Struct definitions with the official schemas (fields, requiredness, enums)."""

from __future__ import annotations

import enum
import typing
from collections.abc import Mapping
from typing import Any

import msgspec


def structs_in(tp: Any) -> list[type[msgspec.Struct]]:
    """Struct classes inside an annotation such as ``list[Node] | None``."""
    if isinstance(tp, type) and issubclass(tp, msgspec.Struct):
        return [tp]
    found: list[type[msgspec.Struct]] = []
    for arg in typing.get_args(tp):
        found += structs_in(arg)
    return found


def enums_in(tp: Any) -> list[type[enum.Enum]]:
    if isinstance(tp, type) and issubclass(tp, enum.Enum):
        return [tp]
    found: list[type[enum.Enum]] = []
    for arg in typing.get_args(tp):
        found += enums_in(arg)
    return found


def _resolve(schema: dict[str, Any], root: dict[str, Any]) -> dict[str, Any]:
    ref = schema.get("$ref")
    if ref is None:
        return schema
    node: Any = root
    for part in ref.removeprefix("#/").split("/"):
        node = node[part]
    result: dict[str, Any] = node
    return result


def _object_schema(prop: dict[str, Any], root: dict[str, Any]) -> dict[str, Any]:
    prop = _resolve(prop, root)
    if prop.get("type") == "array":
        return _resolve(prop["items"], root)
    return prop


def _properties(schema: dict[str, Any]) -> dict[str, Any]:
    """Declared properties, including those of 3.0's ``allOf``/``if``/``then`` branches."""
    merged: dict[str, Any] = {}
    for branch in schema.get("allOf", []):
        merged.update(branch.get("then", {}).get("properties", {}))
    merged.update(schema.get("properties", {}))
    return merged


def compare(
    cls: type[msgspec.Struct],
    schemas: list[tuple[dict[str, Any], dict[str, Any]]],
    where: str,
    extra_fields: Mapping[str, set[str]] | None = None,
    enum_exceptions: Mapping[str, set[str]] | None = None,
) -> list[str]:
    """Differences between a Struct and the (version-specific) object schemas for it."""
    problems: list[str] = []
    fields = {f.encode_name: f for f in msgspec.structs.fields(cls)}
    declared: set[str] = set()
    for schema, _root in schemas:
        declared |= set(_properties(schema))
    missing = declared - set(fields)
    extra = set(fields) - declared - (extra_fields or {}).get(where, set())
    if missing:
        problems.append(f"{where}: {cls.__name__} lacks {sorted(missing)}")
    if extra:
        problems.append(f"{where}: {cls.__name__} has undeclared {sorted(extra)}")
    for wire, field in fields.items():
        relevant = [(s, r) for s, r in schemas if wire in _properties(s)]
        if field.required and any(wire not in s.get("required", []) for s, _ in relevant):
            # A field we require but a schema version does not: valid messages would fail.
            problems.append(f"{where}.{wire}: required in {cls.__name__}, optional in schema")
        for sub in structs_in(field.type):
            subschemas = [(_object_schema(_properties(s)[wire], r), r) for s, r in relevant]
            problems += compare(sub, subschemas, f"{where}.{wire}", extra_fields, enum_exceptions)
        for enum_cls in enums_in(field.type):
            allowed: set[str] = set()
            for s, r in relevant:
                prop = _resolve(_properties(s)[wire], r)
                allowed |= set(prop.get("enum") or prop.get("items", {}).get("enum") or [])
            values = {member.value for member in enum_cls}
            tolerated = (enum_exceptions or {}).get(f"{where}.{wire}", set())
            if allowed and not (allowed <= values and values - allowed <= tolerated):
                problems.append(f"{where}.{wire}: {enum_cls.__name__} {values} != {allowed}")
    return problems
