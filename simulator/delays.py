"""Delay injection: a share of a vehicle's moves start late by a random time.

Traffic management must stay collision- and deadlock-free under any delay (TRAFFIC.md §1.2), so
the simulator can hold a vehicle before an edge it is allowed to drive: with probability `share`
per move it waits a time drawn uniformly from `low`..`high` simulated seconds
(``--delay-share 0.05 --delay-range 5,30``). The decision is made once per move (node sequence
id), from a seeded random generator so runs repeat.
"""

from __future__ import annotations

import random
from dataclasses import dataclass, field


@dataclass(frozen=True, slots=True)
class DelayConfig:
    """How often and how long moves are delayed (share 0: never)."""

    share: float = 0.0
    low: float = 5.0
    high: float = 30.0
    seed: int = 1

    def __post_init__(self) -> None:
        if not 0.0 <= self.share <= 1.0:
            raise ValueError(f"delay share must be within 0..1, got {self.share}")
        if not 0.0 <= self.low <= self.high:
            raise ValueError(f"delay range must be 0 <= low <= high, got {self.low},{self.high}")


def parse_range(text: str) -> tuple[float, float]:
    """``"5,30"`` → (5.0, 30.0) (ValueError for anything else)."""
    parts = text.split(",")
    if len(parts) != 2:
        raise ValueError(f"delay range must be LOW,HIGH seconds, got {text!r}")
    low, high = float(parts[0]), float(parts[1])
    if not 0.0 <= low <= high:
        raise ValueError(f"delay range must be 0 <= LOW <= HIGH, got {text!r}")
    return low, high


@dataclass
class DelayInjector:
    """Per vehicle: whether its current move is held back, and for how long."""

    config: DelayConfig
    stream: int = 0  # vehicles of one fleet get different streams of the same seed
    injected: int = 0
    delayed_seconds: float = 0.0
    _move: object = None
    _until: float = 0.0
    _rng: random.Random = field(init=False)

    def __post_init__(self) -> None:
        self._rng = random.Random(self.config.seed * 1_000_003 + self.stream)

    def holds(self, move: object, now: float) -> bool:
        """Whether the vehicle must still wait before `move` (simulated time `now`)."""
        if move != self._move:
            self._move, self._until = move, now
            if self.config.share > 0 and self._rng.random() < self.config.share:
                delay = self._rng.uniform(self.config.low, self.config.high)
                self._until = now + delay
                self.injected += 1
                self.delayed_seconds += delay
        return now < self._until
