"""Official schema loading and validation helpers for the vda5050 tests."""

from __future__ import annotations

import copy
import functools
import json
import re
from pathlib import Path
from typing import Any

import jsonschema
from jsonschema.protocols import Validator

from vda5050 import (
    TopicKind,
)
from vda5050.topics import kinds_of

# The official schemas live in the shared folder beside the project (CI clones it there too).
SCHEMA_DIR = Path(__file__).resolve().parents[3] / "shared" / "vda5050" / "schemas"
VERSIONS = ("2.0.0", "2.1.0")
#: The six 2.x topic kinds (3.0 adds zoneSet and responses).
KINDS = tuple(kind for kind in TopicKind if kind in kinds_of(2))
#: 3.0 schema folders: main = 3.0.0 + errata (preferred), and the release.
V3_SCHEMA = "3.0.0-main"
V3_RELEASE_SCHEMA = "3.0.0"
KINDS_V3 = tuple(TopicKind)
MANUFACTURER = "Acme"
SERIAL = "AGV-001"
TIMESTAMP = "2024-03-11T11:40:03.12Z"

_TRAILING_COMMA = re.compile(r",(\s*[}\]])")


@functools.cache
def _raw_schema(version: str, kind: str) -> dict[str, Any]:
    text = (SCHEMA_DIR / version / f"{kind}.schema").read_text(encoding="utf-8")
    # REFERENCE §7: some upstream files carry trailing commas.
    result: dict[str, Any] = json.loads(_TRAILING_COMMA.sub(r"\1", text))
    return result


def load_schema(version: str, kind: str, *, patched: bool = True) -> dict[str, Any]:
    """Return a fresh copy of an official schema, optionally with upstream bugs fixed."""
    schema = copy.deepcopy(_raw_schema(version, kind))
    if patched:
        _patch_upstream_bugs(version, kind, schema)
    return schema


def _patch_upstream_bugs(version: str, kind: str, schema: dict[str, Any]) -> None:
    """Fix schema bugs that make document-conformant messages invalid (REFERENCE §7)."""
    if (version, kind) == ("2.1.0", "state"):
        # REFERENCE §5: the 2.1 state schema omits actionStatus PAUSED (the document has it).
        status = schema["properties"]["actionStates"]["items"]["properties"]["actionStatus"]
        status["enum"] = [*status["enum"], "PAUSED"]
    if kind != "factsheet" or not version.startswith("2."):
        return
    action = schema["properties"]["protocolFeatures"]["properties"]["agvActions"]["items"]
    blocking = action["properties"]["blockingTypes"]
    # Upstream puts a string enum on an array, which no array can satisfy.
    blocking["items"] = {"type": "string", "enum": blocking.pop("enum")}
    if version == "2.1.0":
        envelope3d = schema["properties"]["agvGeometry"]["properties"]["envelopes3d"]["items"]
        # 2.1 says "integer" for a free-text description (2.0 and the document: string).
        envelope3d["properties"]["description"]["type"] = "string"


def strictify(schema: Any) -> Any:
    """Forbid properties the schema does not declare, recursively.

    The official schemas allow any extra property, so they cannot notice a misspelt wire
    name or a 2.1-only field sent to a 2.0 vehicle; the strict variant can.
    """
    if isinstance(schema, dict):
        result = {key: strictify(value) for key, value in schema.items()}
        if "properties" in result and "additionalProperties" not in result:
            result["additionalProperties"] = False
            # 3.0 zones declare type-specific properties in allOf/if/then branches.
            conditional = {
                name: {}
                for branch in schema.get("allOf", [])
                for name in branch.get("then", {}).get("properties", {})
            }
            result["properties"] = {**conditional, **result["properties"]}
        return result
    if isinstance(schema, list):
        return [strictify(item) for item in schema]
    return schema


def validator(version: str, kind: str, *, strict: bool = False, patched: bool = True) -> Validator:
    """jsonschema validator of the draft named in the schema's ``$schema``."""
    schema = load_schema(version, kind, patched=patched)
    if strict:
        schema = strictify(schema)
    cls = jsonschema.validators.validator_for(schema)
    cls.check_schema(schema)
    result: Validator = cls(schema)
    return result


def header(version: str, header_id: int = 7) -> dict[str, Any]:
    """Header keyword arguments shared by every sample."""
    return {
        "header_id": header_id,
        "timestamp": TIMESTAMP,
        "version": version,
        "manufacturer": MANUFACTURER,
        "serial_number": SERIAL,
    }
