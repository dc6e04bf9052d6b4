"""Writes of the inventory app: stock from pick/drop and state.loads, discrepancies, CSV.

Inventory sits below orders and beside alerts: it never imports either. Discrepancies are
recorded here (`Discrepancy`, keyed by cause); the orders layer turns open ones into alerts.
"""

from inventory.services.csv_io import export_csv, import_csv
from inventory.services.observe import observe_loads
from inventory.services.stock import (
    define_location,
    move_load,
    record_drop,
    record_pick,
    register_load,
)

__all__ = [
    "define_location",
    "export_csv",
    "import_csv",
    "move_load",
    "observe_loads",
    "record_drop",
    "record_pick",
    "register_load",
]
