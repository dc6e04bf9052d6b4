"""The S3 diagnosis's stop breakdown (`bench.traffic.diagnose.StopCauses`)."""

import math

from bench.traffic.diagnose import StopCauses
from tests.traffic.test_switching import small_warehouse
from traffic.des import SimConfig


def test_every_second_stopped_is_put_down_to_what_the_vehicle_waited_for() -> None:
    m, tasks = small_warehouse(seed=1, vehicles=12)
    config = SimConfig(seed=1, retry_backoff=2.0, reassign_after=3, delay_probability=0.1)
    sim = StopCauses(m, tasks, config)
    stats = sim.run(400.0)
    assert (stats.collisions, stats.wait_cycles, stats.stalls) == (0, 0, 0)
    assert stats.waits  # vehicles did stop
    assert math.isclose(sum(sim.causes.values()), sum(stats.waits))
    assert "unknown" not in sim.causes  # each stop's cause was taken when it began
    assert sim.causes.get("a vehicle late on its move (delay)", 0.0) > 0
    assert set(sim.causes) <= {
        "nobody (own stay)",
        "a vehicle at its route end",
        "a vehicle late on its move (delay)",
        "a vehicle driving",
        "a vehicle waiting itself (queue)",
        "a vehicle standing (turn, handling)",
    }
