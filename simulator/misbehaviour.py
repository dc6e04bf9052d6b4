"""Scripted misbehaviour of one simulated vehicle, for master-control conformance tests.

A :class:`Misbehaviour` only *describes* what a vehicle does wrong; the runtime side is
:class:`simulator.saboteur.Saboteur`. All times are simulated seconds (wall seconds times
the time-lapse factor), counted from the moment the misbehaviour is applied (fleet start
for ``--misbehave``/``--script``). Each field is off by default.

Command line (``--misbehave`` is repeatable; later keys for the same serial win)::

    --misbehave 'AGV-2:reject_orders=orderError,reject_count=2'
    --misbehave 'AGV-1:duplicate_states=0.5,reorder_states=0.2,seed=7'
    --script misbehaviour.json   # [{"serial": "AGV-2", "drop_orders": 1}, ...]
"""

from __future__ import annotations

import json
import math
import re
from collections.abc import Callable, Iterable, Mapping
from dataclasses import dataclass, fields, replace
from pathlib import Path

from vda5050.enums import OperatingMode


@dataclass(frozen=True, slots=True)
class Misbehaviour:
    """What one vehicle does wrong; the default instance behaves perfectly."""

    reject_orders: str | None = None
    """errorType (``validationError``, ``orderError``, ``orderUpdateError``, any vendor
    string) with which new orders and updates are rejected (WARNING, refs orderId and
    orderUpdateId)."""
    reject_count: int | None = None
    """How many orders/updates to reject; None = every one."""
    delay_orders: float = 0.0
    """Seconds an order/update waits before the vehicle processes (accepts) it."""
    drop_orders: int = 0
    """The first N order messages are ignored entirely: no state, no error."""
    duplicate_states: float = 0.0
    """Fraction (0..1) of states published twice with the same headerId."""
    reorder_states: float = 0.0
    """Fraction (0..1) of states held back and published after the next (newer) one."""
    stale_states: float = 0.0
    """Fraction (0..1) of states whose timestamp lies ``stale_age`` seconds in the past."""
    stale_age: float = 60.0
    """Age of a stale state's timestamp in wall seconds (timestamps are wall-clock time)."""
    silent_at: float = 0.0
    silent_for: float = 0.0
    """Publish no state/visualization from ``silent_at`` for this long (0 = never)."""
    disconnect_at: float = 0.0
    disconnect_for: float = 0.0
    """Drop the connection at ``disconnect_at`` (broker sends the last will) and stay away
    for this long before reconnecting with ONLINE (0 = never)."""
    mode: OperatingMode | None = None
    """Operating mode entered at ``mode_at`` (MANUAL/SERVICE/TEACHIN clear the order)."""
    mode_at: float = 0.0
    mode_for: float | None = None
    """Return to the previous mode after this long; None = stay in ``mode``."""
    fail_actions: tuple[str, ...] = ()
    """Action types (``pick``, ``drop``, ...) that end FAILED with an ``actionFailed`` error
    (3.0, if sent ``retriable``: RETRIABLE until the master's retry or skipRetry)."""
    fail_count: int | None = None
    """How many such actions fail; None = every one."""
    fatal_after_nodes: int | None = None
    """Report a FATAL error and stop on the edge after the vehicle passed this many nodes."""
    fatal_error: str = "simulatedFatalError"
    """errorType of that FATAL error (cleared with ``SimulatedFleet.clear_errors``)."""
    seed: int | None = None
    """Seed of the random choices of the state rates; None = derived from the serial."""

    def __post_init__(self) -> None:
        for name in ("duplicate_states", "reorder_states", "stale_states"):
            rate = getattr(self, name)
            if not 0.0 <= rate <= 1.0:
                raise ValueError(f"{name} must be between 0 and 1, got {rate}")
        for name in ("delay_orders", "stale_age", "silent_at", "silent_for", "disconnect_at"):
            _check_seconds(name, getattr(self, name))
        _check_seconds("disconnect_for", self.disconnect_for)
        _check_seconds("mode_at", self.mode_at)
        if self.mode_for is not None:
            _check_seconds("mode_for", self.mode_for)
        for name in ("reject_count", "drop_orders", "fail_count", "fatal_after_nodes"):
            count = getattr(self, name)
            if count is not None and count < 0:
                raise ValueError(f"{name} must be >= 0, got {count}")
        if self.reject_orders is not None and not self.reject_orders:
            raise ValueError("reject_orders must name an errorType")
        if self.mode is not None:
            object.__setattr__(self, "mode", _mode(self.mode))

    @property
    def active(self) -> bool:
        """True if anything differs from a well-behaved vehicle."""
        return self != Misbehaviour(seed=self.seed)

    def __str__(self) -> str:
        """Only the fields that differ from the defaults, e.g. ``drop_orders=1``."""
        changed = [
            f"{f.name}={getattr(self, f.name)}"
            for f in fields(self)
            if getattr(self, f.name) != f.default
        ]
        return ", ".join(changed) or "none"

    @classmethod
    def from_mapping(cls, data: Mapping[str, object]) -> Misbehaviour:
        """Build from JSON-like data: values may be strings (as on the command line) or
        native JSON numbers/lists. Unknown keys raise ValueError."""
        return _update(cls(), data.items())


def _check_seconds(name: str, value: float) -> None:
    if not (math.isfinite(value) and value >= 0.0):
        raise ValueError(f"{name} must be a finite number of seconds >= 0, got {value}")


# ---------------------------------------------------------------------------- conversion
def _number(value: object) -> float:
    if isinstance(value, bool) or not isinstance(value, int | float | str):
        raise ValueError(f"expected a number, got {value!r}")
    return float(value)


def _integer(value: object) -> int:
    number = _number(value)
    if not number.is_integer():
        raise ValueError(f"expected a whole number, got {value!r}")
    return int(number)


def _optional_integer(value: object) -> int | None:
    return None if value in (None, "all", "") else _integer(value)


def _optional_number(value: object) -> float | None:
    return None if value in (None, "") else _number(value)


def _text(value: object) -> str:
    if not isinstance(value, str):
        raise ValueError(f"expected a string, got {value!r}")
    return value


def _mode(value: object) -> OperatingMode | None:
    if value in (None, ""):
        return None
    try:
        return OperatingMode(_text(value).upper())
    except ValueError:
        known = ", ".join(OperatingMode)
        raise ValueError(f"unknown operating mode {value!r} (use {known})") from None


def _names(value: object) -> tuple[str, ...]:
    items = value.split("+") if isinstance(value, str) else value
    if not isinstance(items, list | tuple) or not all(isinstance(i, str) for i in items):
        raise ValueError(f"expected action types like 'pick+drop', got {value!r}")
    return tuple(str(item) for item in items if item)


_CONVERTERS: dict[str, Callable[[object], object]] = {
    "reject_orders": lambda v: None if v in (None, "") else _text(v),
    "reject_count": _optional_integer,
    "delay_orders": _number,
    "drop_orders": _integer,
    "duplicate_states": _number,
    "reorder_states": _number,
    "stale_states": _number,
    "stale_age": _number,
    "silent_at": _number,
    "silent_for": _number,
    "disconnect_at": _number,
    "disconnect_for": _number,
    "mode": _mode,
    "mode_at": _number,
    "mode_for": _optional_number,
    "fail_actions": _names,
    "fail_count": _optional_integer,
    "fatal_after_nodes": _optional_integer,
    "fatal_error": _text,
    "seed": _optional_integer,
}
#: Every key ``--misbehave`` and ``--script`` understand (the field names).
KEYS = tuple(_CONVERTERS)


def _update(base: Misbehaviour, items: Iterable[tuple[str, object]]) -> Misbehaviour:
    changes: dict[str, object] = {}
    for key, raw in items:
        convert = _CONVERTERS.get(key)
        if convert is None:
            raise ValueError(f"unknown misbehaviour {key!r} (known: {', '.join(KEYS)})")
        try:
            changes[key] = convert(raw)
        except ValueError as exc:
            raise ValueError(f"{key}: {exc}") from None
    return replace(base, **changes)  # type: ignore[arg-type]


# ---------------------------------------------------------------------------- CLI forms
_SPEC = re.compile(r"^(?P<serial>.+?):(?P<pairs>[a-z_]+=.*)$")


def parse_spec(text: str) -> tuple[str, list[tuple[str, str]]]:
    """``SERIAL:key=value[,key=value...]`` → (serial, [(key, value), ...])."""
    match = _SPEC.match(text.strip())
    if match is None:
        raise ValueError(f"expected SERIAL:key=value[,key=value...], got {text!r}")
    pairs = []
    for item in match["pairs"].split(","):
        key, sep, value = item.partition("=")
        if not sep or not key.strip():
            raise ValueError(f"expected key=value, got {item!r} in {text!r}")
        pairs.append((key.strip(), value.strip()))
    return match["serial"], pairs


def _script_entries(path: str | Path) -> list[tuple[str, dict[str, object]]]:
    try:
        data = json.loads(Path(path).read_text(encoding="utf-8"))
    except (OSError, json.JSONDecodeError) as exc:
        raise ValueError(f"cannot read misbehaviour script {path}: {exc}") from exc
    if not isinstance(data, list):
        raise ValueError("a misbehaviour script must be a JSON list of objects")
    entries = []
    for entry in data:
        if not isinstance(entry, dict) or not isinstance(entry.get("serial"), str):
            raise ValueError(f"script entry needs a string 'serial': {entry!r}")
        entries.append((entry["serial"], {k: v for k, v in entry.items() if k != "serial"}))
    return entries


def build_plan(
    specs: Iterable[str] = (), script: str | Path | None = None
) -> dict[str, Misbehaviour]:
    """Combine a ``--script`` JSON file (a list of objects with ``serial`` and misbehaviour
    keys) and ``--misbehave`` specs into one :class:`Misbehaviour` per serial. Entries are
    applied in order (script first), so a later key for the same serial wins."""
    plan: dict[str, Misbehaviour] = {}
    entries: list[tuple[str, Iterable[tuple[str, object]]]] = []
    if script is not None:
        entries += [(serial, settings.items()) for serial, settings in _script_entries(script)]
    entries += [parse_spec(spec) for spec in specs]
    for serial, items in entries:
        plan[serial] = _update(plan.get(serial, Misbehaviour()), items)
    return plan
