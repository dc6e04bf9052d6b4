"""Traffic waits as episodes (control.wait_log) and their way out of the controller's flush."""

from datetime import UTC, datetime, timedelta
from types import SimpleNamespace
from typing import Any

from control.wait_log import WaitLog
from tests.control.test_traffic_controller import World

T0 = datetime(2026, 5, 4, 8, 0, tzinfo=UTC)


def vehicle(node: str = "C1", pk: int | None = 7) -> Any:
    return SimpleNamespace(
        pk=pk,
        state=SimpleNamespace(last_node_id=node),
        visual_position=SimpleNamespace(map_id="demo", x=1.0, y=2.0),
    )


def test_a_wait_becomes_one_episode_with_everyone_it_waited_for() -> None:
    log = WaitLog()

    log.observe(vehicle(), [], T0)
    log.observe(vehicle(), ["AGV-2"], T0 + timedelta(seconds=1))
    log.observe(vehicle(), ["AGV-2", "AGV-3"], T0 + timedelta(seconds=5))
    assert log.take_finished() == []  # still waiting
    log.observe(vehicle(), [], T0 + timedelta(seconds=13))

    [episode] = log.take_finished()
    assert episode == {
        "vehicle_id": 7,
        "map_id": "demo",
        "node_id": "C1",
        "x": 1.0,
        "y": 2.0,
        "started_at": T0 + timedelta(seconds=1),
        "seconds": 12.0,
        "waited_for": ["AGV-2", "AGV-3"],
    }
    assert log.take_finished() == []


def test_waiting_again_at_the_next_node_is_a_new_episode() -> None:
    log = WaitLog()

    log.observe(vehicle("C1"), ["AGV-2"], T0)
    log.observe(vehicle("C2"), ["AGV-2"], T0 + timedelta(seconds=4))
    log.observe(vehicle("C2"), [], T0 + timedelta(seconds=6))
    log.observe(vehicle(pk=None), ["AGV-2"], T0)  # not registered yet: nothing to record

    assert [(e["node_id"], e["seconds"]) for e in log.take_finished()] == [("C1", 4.0), ("C2", 2.0)]


def test_the_flush_carries_the_crossing_wait_of_a_real_controller() -> None:
    world = World(["AGV-1", "AGV-2"], traffic=True)
    episodes: list[dict[str, Any]] = []
    collect = world.controller.collect_flush

    def collecting() -> Any:
        batch = collect()
        episodes.extend(batch.traffic_waits)
        return batch

    world.controller.collect_flush = collecting  # type: ignore[method-assign]
    world.run(60.0)
    world.collect()

    assert world.finished == {1, 2}
    assert len(episodes) == 1
    [episode] = episodes
    other = {1: "AGV-2", 2: "AGV-1"}[episode["vehicle_id"]]
    assert episode["waited_for"] == [other]
    assert episode["node_id"]
    assert episode["map_id"]
    assert episode["seconds"] >= 0
