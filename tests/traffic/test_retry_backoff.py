"""A vehicle whose plan keeps failing tries again after growing waits (SimConfig.retry_backoff),
so a goal that stays taken does not cost a full search every second."""

from tests.traffic.helpers import cells, simulate
from traffic.des import SimConfig
from traffic.layout import Layout
from traffic.plans import Goal

CORRIDOR = Layout.grid(cells(["......"]))


def _failures(config: SimConfig) -> int:
    # A stands on B's goal for good (it has nothing to do), so B can never plan.
    stats, _ = simulate(
        CORRIDOR,
        {"A": "0,5", "B": "0,0"},
        {"B": [[Goal("0,5", 1.0)]]},
        until=100.0,
        config=config,
    )
    assert stats.tasks == []
    return stats.plan_failures


def test_constant_retries_by_default() -> None:
    assert _failures(SimConfig(delay_probability=0.0)) == 101  # at 0, 1, ..., 100 s


def test_retries_back_off_to_the_longest_wait() -> None:
    config = SimConfig(delay_probability=0.0, retry_backoff=2.0, retry_max=30.0)
    # tries at 0, 1, 3, 7, 15, 31, then every 30 s: 61, 91
    assert _failures(config) == 8
