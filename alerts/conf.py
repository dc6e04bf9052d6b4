"""Alert thresholds, read from settings with defaults (override any in fleet/settings.py)."""

from django.conf import settings


def low_battery_percent() -> float:
    """Below this charge (and not charging) a vehicle raises a low-battery WARNING."""
    return float(getattr(settings, "ALERTS_LOW_BATTERY_PERCENT", 20.0))


def critical_battery_percent() -> float:
    """Below this charge the low-battery alert becomes CRITICAL."""
    return float(getattr(settings, "ALERTS_CRITICAL_BATTERY_PERCENT", 10.0))


def battery_hysteresis_percent() -> float:
    """An open low-battery alert resolves only this far above the threshold (or when charging),
    so a charge hovering at the threshold does not flap."""
    return float(getattr(settings, "ALERTS_BATTERY_HYSTERESIS_PERCENT", 5.0))


def no_progress_seconds() -> float:
    """A vehicle with an order whose position and last node do not change this long is stuck."""
    return float(getattr(settings, "ALERTS_NO_PROGRESS_SECONDS", 120.0))


def protocol_quiet_seconds() -> float:
    """A protocol-violation alert resolves after this long without a new violation."""
    return float(getattr(settings, "ALERTS_PROTOCOL_QUIET_SECONDS", 300.0))


def protocol_ignored_counters() -> frozenset[str]:
    """Session counters that are not violations (QoS 1 redelivers duplicates by design)."""
    return frozenset(getattr(settings, "ALERTS_PROTOCOL_IGNORED_COUNTERS", ("duplicates",)))


def webhook_timeout_seconds() -> float:
    return float(getattr(settings, "ALERTS_WEBHOOK_TIMEOUT_SECONDS", 5.0))
