"""Settings of the orders app, read at call time: `FLEET_ORDERS` in settings overrides defaults."""

from typing import Any

from django.conf import settings

DEFAULTS: dict[str, Any] = {
    # Seconds an order may stay ASSIGNED without control sending it before the reconciler
    # gives it back to dispatch.
    "ASSIGNMENT_LEASE": 120.0,
    # Seconds dispatch leaves a vehicle alone after it was told to pause, charge or park (until
    # its state shows the pause, or a resume comes), so the command is not overridden at once.
    "COMMAND_HOLD": 120.0,
    # A claimed Idempotency-Key whose request has not completed after this many seconds is
    # taken to be abandoned (its request died) and may be claimed again.
    "IDEMPOTENCY_STALE_AFTER": 60.0,
    "IDEMPOTENCY_TTL": 24 * 3600.0,  # keys are kept this long, then pruned
    # What happens to the active orders of a vehicle that is offline, unreachable, has a FATAL
    # error or is in manual mode for LOST_VEHICLE_GRACE seconds: "wait" (it keeps them and
    # resumes when back, as VDA 5050 intends), "reassign" (orders it never received go back to
    # dispatch; the others wait) or "fail" (orders it never received fail; the others are
    # cancelled, which control carries out when the vehicle is back). Recorded on each order.
    "LOST_VEHICLE_POLICY": "wait",
    "LOST_VEHICLE_GRACE": 120.0,
    "WEBHOOK_TIMEOUT": 5.0,  # seconds for connect and for each read of one attempt
    "WEBHOOK_MAX_ATTEMPTS": 8,
    "WEBHOOK_RETRY_BASE": 10.0,  # seconds before the 2nd attempt; doubles each time
    "WEBHOOK_RETRY_CAP": 3600.0,
    "WEBHOOK_LOG_DAYS": 30,  # finished deliveries and their attempt logs are kept this long
}


def setting(name: str) -> Any:
    """The value of `name` from settings.FLEET_ORDERS, else its default."""
    return getattr(settings, "FLEET_ORDERS", {}).get(name, DEFAULTS[name])
