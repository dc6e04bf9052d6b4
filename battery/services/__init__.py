"""Writes of the battery app: snapshot observation, charging jobs, chargers and policies."""

from battery.services.charging import (
    apply_charge_progress,
    cancel_session,
    create_missing_chargers,
    plan_charging,
    point_node,
    request_charge,
)
from battery.services.observe import OBSERVER, observe_snapshots

__all__ = [
    "OBSERVER",
    "apply_charge_progress",
    "cancel_session",
    "create_missing_chargers",
    "observe_snapshots",
    "plan_charging",
    "point_node",
    "request_charge",
]
