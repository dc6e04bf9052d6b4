"""The charging policy and the consumption model as pure logic (no Django, no database).

The services feed them from rows, the energy benchmark feeds them from a simulation: both take
the same decisions. Charge levels are percent.
"""

import enum
from dataclasses import dataclass

# How quickly the learned rates follow new observations (per observation window).
LEARNING_RATE = 0.2
# Observations shorter than this carry too little signal to learn from.
MIN_METRES = 5.0
MIN_SECONDS = 60.0


class Band(enum.StrEnum):
    """Where a charge level stands against a policy."""

    CRITICAL = "CRITICAL"
    NEEDS_CHARGE = "NEEDS_CHARGE"
    WORKING = "WORKING"
    SUFFICIENT = "SUFFICIENT"
    FULL = "FULL"


class Reason(enum.StrEnum):
    """Why a vehicle should charge, most urgent first (the queue order)."""

    CRITICAL = "CRITICAL"
    LOW = "LOW"
    MANUAL = "MANUAL"
    OPPORTUNITY = "OPPORTUNITY"


URGENCY = {Reason.CRITICAL: 0, Reason.LOW: 1, Reason.MANUAL: 2, Reason.OPPORTUNITY: 3}


@dataclass(frozen=True)
class Levels:
    """A charging policy (see `battery.models.ChargingPolicy` for the meaning of each level)."""

    critical: float = 15.0
    needs_charge: float = 30.0
    sufficient: float = 60.0
    charge_until: float = 90.0
    full: float = 98.0
    opportunity_charging: bool = True
    opportunity_below: float = 80.0
    shift_reserve_hours: float = 0.0

    def working_minimum(self, drain_per_hour: float | None = None) -> float:
        """Below this a vehicle takes no new work: `needs_charge`, raised by the shift reserve
        (the learned consumption of `shift_reserve_hours` of work above critical)."""
        reserve = self.critical + (drain_per_hour or 0.0) * self.shift_reserve_hours
        return max(self.needs_charge, min(reserve, self.sufficient))

    def band(self, charge: float, drain_per_hour: float | None = None) -> Band:
        if charge < self.critical:
            return Band.CRITICAL
        if charge < self.working_minimum(drain_per_hour):
            return Band.NEEDS_CHARGE
        if charge >= self.full:
            return Band.FULL
        if charge >= self.sufficient:
            return Band.SUFFICIENT
        return Band.WORKING

    def charge_reason(
        self,
        charge: float,
        *,
        idle: bool,
        work_waiting: bool,
        drain_per_hour: float | None = None,
    ) -> Reason | None:
        """Whether a vehicle should go charging now, and why. Busy vehicles finish their job
        first (dispatch already refused them jobs they could not finish above critical)."""
        if not idle:
            return None
        band = self.band(charge, drain_per_hour)
        if band is Band.CRITICAL:
            return Reason.CRITICAL
        if band is Band.NEEDS_CHARGE:
            return Reason.LOW
        if self.opportunity_charging and not work_waiting and charge < self.opportunity_below:
            return Reason.OPPORTUNITY
        return None

    def stop_charging(self, charge: float, *, work_waiting: bool, queue_waiting: bool) -> bool:
        """Whether a charging vehicle should stop: charged up to `charge_until`, or charged
        enough (`sufficient`) while work or another vehicle waits for the point."""
        if charge >= self.charge_until:
            return True
        return (work_waiting or queue_waiting) and charge >= self.sufficient

    def job_refusal(
        self, charge: float | None, job_use: float, drain_per_hour: float | None = None
    ) -> str | None:
        """Why a vehicle at `charge` must not take a job that uses `job_use` percent, or None.

        The projected charge after the job must stay above the critical level plus what the
        drive to a charger needs (`job_use` includes it when the caller knows the distance)."""
        if charge is None:
            return None  # a vehicle that reports no battery is not held back
        minimum = self.working_minimum(drain_per_hour)
        if charge < minimum:
            return f"battery {charge:.0f}% below {minimum:.0f}%: needs charge"
        projected = charge - job_use
        if projected < self.critical:
            critical = self.critical
            return f"battery would drop to {projected:.0f}% on this job (critical {critical:.0f}%)"
        return None


@dataclass
class Consumption:
    """A vehicle's learned consumption: percent per metre driven and per hour standing.

    Standing covers actions (pick, drop) and idling; a job's projection adds the metres of its
    route and the standing time of its actions.
    """

    per_metre: float | None = None
    per_hour: float | None = None
    fallback_per_metre: float = 0.05  # the simulator's default until something is learned
    fallback_per_hour: float = 7.2

    def observe(self, *, used: float, metres: float, seconds: float) -> None:
        """Learn from `used` percent over `metres` driven in `seconds` (not charging).

        Standing drain is taken from the time share, the rest is put on the metres."""
        if used < 0 or seconds <= 0:
            return
        hourly = self.per_hour if self.per_hour is not None else self.fallback_per_hour
        if metres >= MIN_METRES:
            driving_use = max(0.0, used - hourly * seconds / 3600.0)
            self.per_metre = _blend(self.per_metre, driving_use / metres)
        elif seconds >= MIN_SECONDS:
            self.per_hour = _blend(self.per_hour, used / seconds * 3600.0)

    def project(self, *, metres: float, standing_seconds: float = 0.0) -> float:
        """Percent a job of `metres` with `standing_seconds` of actions would use."""
        per_metre = self.per_metre if self.per_metre is not None else self.fallback_per_metre
        per_hour = self.per_hour if self.per_hour is not None else self.fallback_per_hour
        return metres * per_metre + standing_seconds * per_hour / 3600.0


def _blend(old: float | None, new: float) -> float:
    return new if old is None else old + LEARNING_RATE * (new - old)
