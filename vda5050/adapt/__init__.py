"""Dual-version adapters between VDA 5050 2.x and 3.0.0 (REFERENCE §6).

Master control keeps one model, the 2.x Structs: what a 3.0 robot sends is adapted with
:func:`state_v3_to_v2`, :func:`factsheet_v3_to_v2`, :func:`connection_v3_to_v2` and
:func:`visualization_v3_to_v2`; what master control builds in 2.x goes out through
:func:`order_v2_to_v3` and :func:`instant_actions_v2_to_v3`. The inverse adapters serve
the robot side (the simulator speaking 3.0) and round-trip tests. Each module's docstring
lists its field mapping; :mod:`vda5050.adapt.common` explains how values without a 2.x
equivalent are kept (3.0 strings, RETRIABLE and error-level markers).
"""

from __future__ import annotations

from vda5050.adapt.common import (
    ACTION_TYPES_V2_TO_V3,
    ACTION_TYPES_V3_TO_V2,
    ERROR_LEVEL_KEY,
    RETRIABLE_MARKER,
    action_type_v2,
    action_type_v3,
    error_level_v3,
    is_retriable,
    retriable_result,
)
from vda5050.adapt.factsheet import factsheet_v3_to_v2
from vda5050.adapt.messages import (
    connection_v2_to_v3,
    connection_v3_to_v2,
    position_to_v2,
    position_to_v3,
    visualization_v2_to_v3,
    visualization_v3_to_v2,
)
from vda5050.adapt.order import (
    RetriableAction,
    action_to_v2,
    action_to_v3,
    instant_actions_v2_to_v3,
    instant_actions_v3_to_v2,
    order_v2_to_v3,
    order_v3_to_v2,
)
from vda5050.adapt.state import state_v2_to_v3, state_v3_to_v2

__all__ = [
    "ACTION_TYPES_V2_TO_V3",
    "ACTION_TYPES_V3_TO_V2",
    "ERROR_LEVEL_KEY",
    "RETRIABLE_MARKER",
    "RetriableAction",
    "action_to_v2",
    "retriable_result",
    "action_to_v3",
    "action_type_v2",
    "action_type_v3",
    "connection_v2_to_v3",
    "connection_v3_to_v2",
    "error_level_v3",
    "factsheet_v3_to_v2",
    "instant_actions_v2_to_v3",
    "instant_actions_v3_to_v2",
    "is_retriable",
    "order_v2_to_v3",
    "order_v3_to_v2",
    "position_to_v2",
    "position_to_v3",
    "state_v2_to_v3",
    "state_v3_to_v2",
    "visualization_v2_to_v3",
    "visualization_v3_to_v2",
]
