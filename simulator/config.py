"""Static configuration of one simulated vehicle: its parameters and where it boots."""

from __future__ import annotations

import math
from dataclasses import dataclass

from simulator.misbehaviour import Misbehaviour
from vda5050.versions import major_of

__all__ = ["StartPose", "VehicleConfig", "normalize_angle"]


@dataclass(frozen=True, slots=True)
class VehicleConfig:
    """Static parameters of one simulated vehicle (speeds in m/s, battery in %)."""

    serial_number: str = "AGV-1"
    manufacturer: str = "sim"
    version: str = "2.0.0"
    speed: float = 1.0
    time_scale: float = 1.0
    start_reach: float = 0.5
    state_interval: float = 30.0
    visualization_hz: float = 1.0
    battery_start: float = 100.0
    battery_drain_per_metre: float = 0.05
    battery_idle_drain_per_second: float = 0.002
    battery_charge_per_second: float = 1.0
    map_version: str = "1"
    misbehaviour: Misbehaviour = Misbehaviour()

    @property
    def wall_speed(self) -> float:
        """The top speed a master control sees on its wall clock (the factsheet's speedMax):
        with `time_scale` the vehicle covers that many simulated seconds per wall second, and
        plans made at the simulated speed would be `time_scale` times too slow."""
        return self.speed * self.time_scale

    @property
    def major(self) -> int:
        """Protocol major version (2 for 2.0/2.1, 3 for 3.0): selects the message edge."""
        return major_of(self.version)


@dataclass(frozen=True, slots=True)
class StartPose:
    """Where a vehicle boots: on ``node_id`` of ``map_id`` at (x, y, theta)."""

    map_id: str
    node_id: str
    x: float
    y: float
    theta: float = 0.0


def normalize_angle(theta: float) -> float:
    """Wrap an angle to [-pi, pi] as the protocol requires."""
    return math.atan2(math.sin(theta), math.cos(theta))
