"""Typed reads of the fields of a decoded JSON payload, for the layout editor's payload reader.

Each read notes a problem with its JSONPath-like path ("$.edges[4].maxSpeed") and returns a
fallback instead of raising, so one pass over a payload finds every problem in it.
"""

import math
from dataclasses import dataclass
from typing import Any


@dataclass(frozen=True)
class Problem:
    """One problem of a payload: where (JSONPath-like) and what."""

    path: str
    message: str

    def as_dict(self) -> dict[str, str]:
        return {"path": self.path, "message": self.message}


def show_value(value: Any) -> str:
    """A short rendering of a payload value for messages."""
    text = repr(value)
    return text if len(text) <= 40 else text[:37] + "..."


class FieldReader:
    """Reads fields of JSON objects; problems collect in `problems`, reads return a fallback."""

    def __init__(self) -> None:
        self.problems: list[Problem] = []

    def _number(
        self,
        data: dict[str, Any],
        key: str,
        path: str,
        *,
        required: bool = False,
        positive: bool = False,
        unit: bool = False,
    ) -> float | None:
        value = data.get(key)
        if value is None:
            if required:
                self._problem(f"{path}.{key}", "missing")
            return None
        if (
            isinstance(value, bool)
            or not isinstance(value, int | float)
            or not math.isfinite(value)
        ):
            self._problem(f"{path}.{key}", f"must be a number, not {show_value(value)}")
            return None
        if positive and value <= 0:
            self._problem(f"{path}.{key}", "must be above 0")
            return None
        if unit and not 0 <= value <= 1:
            self._problem(f"{path}.{key}", "must be from 0 to 1")
            return None
        return float(value)

    def _text(self, data: dict[str, Any], key: str, path: str, max_length: int) -> str:
        value = data.get(key)
        if value is None:
            return ""
        if not isinstance(value, str):
            self._problem(f"{path}.{key}", "must be text")
            return ""
        if len(value) > max_length:
            self._problem(f"{path}.{key}", f"longer than {max_length} characters")
        return value[:max_length]

    def _flag(self, data: dict[str, Any], key: str, path: str, *, default: bool) -> bool:
        value = data.get(key, default)
        if not isinstance(value, bool):
            self._problem(f"{path}.{key}", "must be true or false")
            return default
        return value

    def _choice(self, data: dict[str, Any], key: str, path: str, choices: list[str]) -> str:
        value = data.get(key) or ""
        if value and value not in choices:
            self._problem(f"{path}.{key}", f"must be one of {', '.join(choices)}")
            return ""
        return str(value)

    def _object(self, value: Any, path: str) -> dict[str, Any] | None:
        if not isinstance(value, dict):
            self._problem(path, "must be an object")
            return None
        return value

    def _list(self, data: dict[str, Any], key: str, path: str) -> list[Any]:
        value = data.get(key)
        if not isinstance(value, list):
            self._problem(f"{path}.{key}", "missing" if value is None else "must be a list")
            return []
        return value

    def _known(self, data: dict[str, Any], path: str, keys: set[str]) -> None:
        for key in data:
            if key not in keys:
                self._problem(f"{path}.{key}", "unknown field")

    def _problem(self, path: str, message: str) -> None:
        self.problems.append(Problem(path, message))
