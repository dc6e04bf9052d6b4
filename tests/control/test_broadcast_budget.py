"""The live page's broadcast interval stretches with the fleet (FLEET_BROADCAST_ROWS_PER_S)."""

from typing import Any

import pytest

from control.controller import Controller
from control.runner import ControlLoop
from tests.control.fakes import FakeStore


def _loop(**intervals: float) -> ControlLoop:
    controller = Controller(store=FakeStore(), interface_name="uagv", publish=lambda *a: None)
    link: Any = object()
    return ControlLoop(
        controller,
        link,
        receive_commands=lambda timeout: [],
        broadcast=lambda rows: None,
        intervals={"BROADCAST_INTERVAL": 0.2, **intervals},
    )


@pytest.mark.parametrize(
    ("rows", "pause"),
    [
        (0, 0.2),  # nothing changed: the next look is one interval away
        (150, 0.2),  # a small fleet: every interval, as before
        (200, 0.2),  # exactly the budget's rate
        (500, 0.5),  # 500 rows at 1,000 a second: half a second
        (1_000, 1.0),  # 1,000 moving vehicles: about once a second
    ],
)
def test_the_pause_keeps_the_rows_built_per_second_within_the_budget(
    rows: int, pause: float
) -> None:
    loop = _loop(BROADCAST_ROWS_PER_S=1000.0)
    assert loop._broadcast_pause(rows) == pytest.approx(pause)


def test_no_budget_keeps_the_fixed_interval() -> None:
    assert _loop()._broadcast_pause(5_000) == 0.2
    assert _loop(BROADCAST_ROWS_PER_S=0.0)._broadcast_pause(5_000) == 0.2
