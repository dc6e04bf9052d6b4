"""Writes of the alerts app: raise, dedup, acknowledge and resolve alerts (issue 8).

Other apps call `raise_alert(...)` when a cause appears and `resolve_alert(cause)` when it clears;
both are idempotent, so callers need not remember what they raised. Alerts sit below orders:
callers pass plain values (an order reference string, a vehicle pk), never order objects.
"""

from alerts.services.core import (
    acknowledge_alert,
    raise_alert,
    resolve_alert,
    resolve_by_user,
    sync_causes,
)
from alerts.services.escalation import escalate_alerts
from alerts.services.observe import observe_snapshots

__all__ = [
    "acknowledge_alert",
    "escalate_alerts",
    "observe_snapshots",
    "raise_alert",
    "resolve_alert",
    "resolve_by_user",
    "sync_causes",
]
