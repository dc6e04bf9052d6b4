"""Writes of the maintenance app: counters from state, service plans, work orders, service."""

from maintenance.services.moves import apply_move_progress, send_to_station
from maintenance.services.observe import OBSERVER, observe_snapshots
from maintenance.services.work import (
    add_attachment,
    advance_work_order,
    check_service_plans,
    create_work_order,
    return_to_service,
    take_out_of_service,
)

__all__ = [
    "OBSERVER",
    "add_attachment",
    "advance_work_order",
    "apply_move_progress",
    "check_service_plans",
    "create_work_order",
    "observe_snapshots",
    "return_to_service",
    "send_to_station",
    "take_out_of_service",
]
