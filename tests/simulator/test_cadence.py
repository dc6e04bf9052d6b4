"""The periodic messages of a vehicle link keep their configured rate when the tick loop runs
late: a state every `state_interval`, not every interval plus a tick's lateness (pure timing
logic, on a made-up clock; the broker is not involved)."""

from __future__ import annotations

import random

import pytest

from simulator.mqtt import BrokerSettings, VehicleLink
from tests.simulator.builders import make_vehicle


class CountingLink(VehicleLink):
    """A link that counts its sends instead of writing them to a socket."""

    def __init__(self, state_interval: float, visualization_hz: float) -> None:
        vehicle = make_vehicle(state_interval=state_interval, visualization_hz=visualization_hz)
        super().__init__(vehicle, BrokerSettings(), "cadence")
        self.client.is_connected = lambda: True  # type: ignore[method-assign]
        self.sent: dict[str, int] = {"state": 0, "visualization": 0}
        self.client.publish = self._count  # type: ignore[method-assign]

    def _count(self, topic: str, *_args: object, **_kwargs: object) -> None:
        kind = topic.rsplit("/", 1)[1]
        if kind in self.sent:
            self.sent[kind] += 1


def drive(link: CountingLink, seconds: float, late: float, seed: int = 1) -> None:
    """Tick the link every 0.1 s plus up to `late` seconds of lateness, for `seconds`."""
    rng = random.Random(seed)
    now = 0.0
    while now < seconds:
        step = 0.1 + rng.random() * late
        now += step
        link.pump(step, now)


@pytest.mark.parametrize("late", [0.0, 0.1, 0.3])
def test_the_periodic_state_keeps_its_interval_when_ticks_come_late(late: float) -> None:
    link = CountingLink(state_interval=0.5, visualization_hz=2.0)
    drive(link, 60.0, late)
    # 60 s at one state per 0.5 s: 120 (the first tick sends at once, the last may fall short).
    assert 119 <= link.sent["state"] <= 121, link.sent
    assert 119 <= link.sent["visualization"] <= 121, link.sent


def test_a_stall_does_not_burst_to_catch_up() -> None:
    link = CountingLink(state_interval=0.5, visualization_hz=2.0)
    drive(link, 5.0, 0.0)
    before = dict(link.sent)
    link.pump(0.1, 15.0)  # ten seconds without a tick
    assert link.sent == {kind: n + 1 for kind, n in before.items()}
    link.pump(0.1, 15.1)  # the next period counts from the late send
    assert link.sent == {kind: n + 1 for kind, n in before.items()}
    link.pump(0.1, 15.5)
    assert link.sent == {kind: n + 2 for kind, n in before.items()}
