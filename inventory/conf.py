"""Inventory settings with defaults (override in fleet/settings.py)."""

from django.conf import settings


def discrepancy_grace_seconds() -> float:
    """How long a mismatch between state.loads and the inventory must persist before it counts.

    A vehicle may report a picked load a state or two before (or after) control applies the
    pick's FINISHED: a short grace keeps those races from raising alerts.
    """
    return float(getattr(settings, "INVENTORY_DISCREPANCY_GRACE_SECONDS", 5.0))
