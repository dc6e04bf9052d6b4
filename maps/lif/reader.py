"""Typed reads from decoded JSON that note every problem with its path instead of stopping."""

import json
import math
from collections.abc import Iterable
from typing import Any

from maps.lif.report import ImportReport


def show(value: Any) -> str:
    """A short rendering of a JSON value for messages."""
    text = json.dumps(value, ensure_ascii=False, default=str)
    return text if len(text) <= 40 else text[:37] + "..."


def kind_of(value: Any) -> str:
    names = {dict: "an object", list: "an array", str: "a string", bool: "a boolean"}
    if value is None:
        return "null"
    if isinstance(value, int | float) and not isinstance(value, bool):
        return "a number"
    return names.get(type(value), type(value).__name__)


class Reader:
    """Reads fields of JSON objects; problems go to the report, reads return a fallback."""

    def __init__(self, report: ImportReport) -> None:
        self.report = report
        self._unknown: dict[tuple[str, str], list[Any]] = {}

    def obj(self, value: Any, path: str) -> dict[str, Any] | None:
        if isinstance(value, dict):
            return value
        self.report.error(path, f"expected an object, got {kind_of(value)}")
        return None

    def known(self, data: dict[str, Any], path: str, what: str, keys: Iterable[str]) -> None:
        """Note fields LIF does not define (reported once per kind of object and field)."""
        for key in data.keys() - set(keys):
            entry = self._unknown.setdefault((what, key), [f"{path}.{key}", 0])
            entry[1] += 1

    def flush_unknown(self) -> None:
        for (what, key), (path, count) in self._unknown.items():
            where = f" (in {count} {what}s)" if count > 1 else ""
            self.report.warn(path, f'unknown field "{key}" ignored{where}')

    def string(self, data: dict[str, Any], key: str, path: str, *, required: bool = False) -> str:
        value = data.get(key)
        if value is None:
            if required:
                self.report.error(f"{path}.{key}", "missing required field")
            return ""
        if isinstance(value, str):
            if required and not value.strip():
                self.report.error(f"{path}.{key}", "must not be empty")
            return value
        self.report.error(f"{path}.{key}", f"expected a string, got {kind_of(value)}")
        return ""

    def number(
        self,
        data: dict[str, Any],
        key: str,
        path: str,
        *,
        required: bool = False,
        minimum: float | None = None,
        positive: bool = False,
        lenient: bool = False,
    ) -> float | None:
        """A finite number; with `lenient`, a numeric string is read with a warning."""
        value, where = data.get(key), f"{path}.{key}"
        if value is None:
            if required:
                self.report.error(where, "missing required field")
            return None
        if lenient and isinstance(value, str):
            try:
                number = float(value)
            except ValueError:
                self.report.error(where, f"expected a number, got {show(value)}")
                return None
            self.report.warn(where, f"number given as a string {show(value)}; read as {number:g}")
            value = number
        if not isinstance(value, int | float) or isinstance(value, bool):
            self.report.error(where, f"expected a number, got {kind_of(value)}")
            return None
        if not math.isfinite(value):
            self.report.error(where, f"must be a finite number, got {value}")
            return None
        if minimum is not None and value < minimum:
            self.report.error(where, f"must be at least {minimum:g}, got {value:g}")
            return None
        if positive and value <= 0:
            self.report.error(where, f"must be greater than 0, got {value:g}")
            return None
        return float(value)

    def boolean(
        self, data: dict[str, Any], key: str, path: str, *, required: bool = False
    ) -> bool | None:
        value = data.get(key)
        if value is None:
            if required:
                self.report.error(f"{path}.{key}", "missing required field")
            return None
        if isinstance(value, bool):
            return value
        self.report.error(f"{path}.{key}", f"expected true or false, got {show(value)}")
        return None

    def choice(
        self,
        data: dict[str, Any],
        key: str,
        path: str,
        choices: Iterable[str],
        *,
        required: bool = False,
    ) -> str:
        value = self.string(data, key, path, required=required)
        allowed = list(choices)
        if value and value not in allowed:
            self.report.error(f"{path}.{key}", f"{show(value)} is not one of {', '.join(allowed)}")
            return ""
        return value

    def array(
        self, data: dict[str, Any], key: str, path: str, *, required: bool = False
    ) -> list[Any] | None:
        value = data.get(key)
        if value is None:
            if required:
                self.report.error(f"{path}.{key}", "missing required field")
            return None
        if isinstance(value, list):
            return value
        self.report.error(f"{path}.{key}", f"expected an array, got {kind_of(value)}")
        return None

    def strings(self, data: dict[str, Any], key: str, path: str) -> list[str] | None:
        values = self.array(data, key, path)
        if values is None:
            return None
        for i, value in enumerate(values):
            if not isinstance(value, str):
                self.report.error(f"{path}.{key}[{i}]", f"expected a string, got {kind_of(value)}")
        return [v for v in values if isinstance(v, str)]
