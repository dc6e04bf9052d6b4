"""Value mappings shared by the 2.x ↔ 3.0 adapters (REFERENCE §5, §6).

Enum values are mapped by spelling (``TEACH_IN`` ↔ ``TEACHIN``, ``CONNECTION_BROKEN`` ↔
``CONNECTIONBROKEN``, ...). A 3.0 value without a 2.x equivalent (operating modes STARTUP and
INTERVENED, connection HIBERNATING, blockingType SINGLE, action scope ZONE, extensible
factsheet values) is kept as its plain 3.0 string in the 2.x Struct: msgspec does not check
types on construction, ``str(field)`` gives the 3.0 spelling master control gates on, and the
reverse adapters restore the 3.0 member. Such a Struct no longer validates against a 2.x
schema, which is intended: it must never be sent to a 2.x vehicle.

Two lossy 3.0 → 2.x mappings leave a marker so the original can be told (and restored):

* actionStatus RETRIABLE → PAUSED (not terminal, so the order is not considered done) with
  ``resultDescription`` ``"RETRIABLE"`` or ``"RETRIABLE: <actionResult>"`` → :func:`is_retriable`.
* errorLevel URGENT → WARNING and CRITICAL → FATAL, with an extra error reference
  ``{"referenceKey": "errorLevel", "referenceValue": "URGENT"|"CRITICAL"}`` →
  :func:`error_level_v3`.
"""

from __future__ import annotations

from collections.abc import Mapping
from enum import StrEnum
from typing import TypeVar, cast

from vda5050 import v2, v3
from vda5050.enums import ActionStatus, ErrorLevel

__all__ = [
    "ACTION_TYPES_V2_TO_V3",
    "ACTION_TYPES_V3_TO_V2",
    "ERROR_LEVEL_KEY",
    "RETRIABLE_MARKER",
    "action_type_v2",
    "action_type_v3",
    "error_level_v3",
    "is_retriable",
    "to_v2",
    "to_v3",
]

E = TypeVar("E", bound=StrEnum)

#: Predefined actions renamed in 3.0 (REFERENCE §6 "actions").
ACTION_TYPES_V2_TO_V3: Mapping[str, str] = {"initPosition": "initializePosition"}
ACTION_TYPES_V3_TO_V2: Mapping[str, str] = {v: k for k, v in ACTION_TYPES_V2_TO_V3.items()}

#: ``resultDescription`` prefix of an action that was RETRIABLE in 3.0.
RETRIABLE_MARKER = "RETRIABLE"
#: ``referenceKey`` of the error reference carrying a 3.0 error level that 2.x lacks.
ERROR_LEVEL_KEY = "errorLevel"

# 3.0 spelling → 2.x spelling, for values whose name changed.
SPELLING_V3_TO_V2: Mapping[str, str] = {
    "TEACH_IN": "TEACHIN",
    "CONNECTION_BROKEN": "CONNECTIONBROKEN",
    "KINEMATIC_CENTER": "KINEMATICCENTER",
    "DIFFERENTIAL": "DIFF",
    "OMNIDIRECTIONAL": "OMNI",
    "THREE_WHEEL": "THREEWHEEL",
    "FREELY_NAVIGATING": "AUTONOMOUS",
}
SPELLING_V2_TO_V3: Mapping[str, str] = {v: k for k, v in SPELLING_V3_TO_V2.items()}


def to_v2(enum_cls: type[E], value: str) -> E:
    """``value`` (a 3.0 enum value) as member of the 2.x ``enum_cls``, renamed if needed;
    a value 2.x does not have is returned as its plain 3.0 string (see module docstring)."""
    name = SPELLING_V3_TO_V2.get(str(value), str(value))
    try:
        return enum_cls(name)
    except ValueError:
        return cast(E, str(value))


def to_v3(enum_cls: type[E], value: str) -> E:
    """``value`` (a 2.x enum value or a kept 3.0 string) as member of the 3.0 ``enum_cls``.

    Raises:
        ValueError: if the value has no 3.0 equivalent.
    """
    return enum_cls(SPELLING_V2_TO_V3.get(str(value), str(value)))


def to_v3_text(value: str) -> str:
    """An extensible-enum value (kinematics, navigation type, ...) in 3.0 spelling."""
    return SPELLING_V2_TO_V3.get(str(value), str(value))


def to_v2_text(value: str) -> str:
    """An extensible-enum value in 2.x spelling (unknown values unchanged)."""
    return SPELLING_V3_TO_V2.get(str(value), str(value))


def action_type_v2(action_type: str) -> str:
    """2.x name of an action type (``initializePosition`` → ``initPosition``)."""
    return ACTION_TYPES_V3_TO_V2.get(action_type, action_type)


def action_type_v3(action_type: str) -> str:
    """3.0 name of an action type (``initPosition`` → ``initializePosition``)."""
    return ACTION_TYPES_V2_TO_V3.get(action_type, action_type)


def is_retriable(action_state: v2.ActionState) -> bool:
    """True if an adapted action state was RETRIABLE in 3.0: the vehicle waits for
    ``retry`` or ``skipRetry`` (REFERENCE §3 E.27)."""
    result = action_state.result_description or ""
    return action_state.action_status == ActionStatus.PAUSED and (
        result == RETRIABLE_MARKER or result.startswith(RETRIABLE_MARKER + ": ")
    )


def error_level_v3(error: v2.Error) -> v3.ErrorLevel:
    """The 3.0 level of an adapted error (URGENT/CRITICAL survive as a reference)."""
    for ref in error.error_references or ():
        if ref.reference_key == ERROR_LEVEL_KEY and ref.reference_value in ("URGENT", "CRITICAL"):
            return v3.ErrorLevel(ref.reference_value)
    return v3.ErrorLevel.FATAL if error.error_level == ErrorLevel.FATAL else v3.ErrorLevel.WARNING


def retriable_result(action_result: str | None) -> str:
    """The 2.x ``resultDescription`` that marks a RETRIABLE action."""
    return RETRIABLE_MARKER if not action_result else f"{RETRIABLE_MARKER}: {action_result}"


def unmark_retriable(result: str | None) -> str | None:
    """The 3.0 ``actionResult`` hidden in a marked ``resultDescription``."""
    text = (result or "").removeprefix(RETRIABLE_MARKER).removeprefix(": ")
    return text or None
