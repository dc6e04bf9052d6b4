"""Idle vehicles in an order's way are sent to park (control/parking.py), in process.

The real Controller drives in-process simulated vehicles (as in test_traffic_controller.py) on a
one-lane corridor with two park spurs. An idle vehicle stands on the goal, or in the passage, of
the other vehicle's order: without parking that order never starts; with it the idle vehicle
is sent to a park station (a `vehicle.park` job, opened here like the flush would) and the order
finishes, with no collision seen by the simulator's checker.
"""

import dataclasses
import time
from collections import deque
from typing import Any

import pytest

from control import parking
from control.execution import LayoutIndex, NodePlace
from control.ports import ActiveOrder
from tests.control.sim_world import SimWorld

SPACING = 2.0  # m between nodes: neighbours are free of each other


def corridor() -> LayoutIndex:
    """W1 … W5 in a row (one lane, both ways); park spurs PK-1 above W2 and PK-2 above W4."""
    nodes = {f"W{i}": NodePlace((i - 1) * SPACING, 0.0, None, "hall") for i in range(1, 6)}
    nodes["PK1"] = NodePlace(SPACING, SPACING, None, "hall")
    nodes["PK2"] = NodePlace(3 * SPACING, SPACING, None, "hall")
    pairs = [(f"W{i}", f"W{i + 1}") for i in range(1, 5)] + [("W2", "PK1"), ("W4", "PK2")]
    edges = {}
    for a, b in pairs:
        edges[(a, b)], edges[(b, a)] = f"{a}-{b}", f"{b}-{a}"
    return LayoutIndex("hall", nodes, edges, parking={"PARK-1": "PK1", "PARK-2": "PK2"})


LAYOUT = corridor()


def shortest(start: str, goal: str) -> list[str]:
    """Breadth-first route on LAYOUT (what the database's move would carry)."""
    previous: dict[str, str | None] = {start: None}
    queue = deque([start])
    while queue:
        node = queue.popleft()
        for a, b in LAYOUT.edges:
            if a == node and b not in previous:
                previous[b] = node
                queue.append(b)
    route = [goal]
    while (step := previous[route[-1]]) is not None:
        route.append(step)
    return route[::-1]


class World(SimWorld):
    """Vehicles on the corridor and the controller; park jobs are opened like the flush does."""

    def __init__(self, starts: dict[str, str], *, park_idle: bool) -> None:
        super().__init__(LAYOUT, starts, traffic=True, park_idle=park_idle)
        self.park_jobs: list[dict[str, Any]] = []

    def transport(self, serial: str, pickup: str, drop: str) -> None:
        vehicle = self.vehicles[serial]
        self.orders.append(
            ActiveOrder(
                transport_order_id=len(self.orders) + 1,
                vda_order_id=f"TO-{len(self.orders) + 1}",
                vehicle_pk=self.serials.index(serial) + 1,
                route=shortest(vehicle.last_node_id, drop),
                pickup_node=pickup,
                map_id="hall",
                pick_station="PICK",
                drop_station="DROP",
            )
        )

    def take_jobs(self, jobs: list[dict[str, Any]]) -> None:
        for job in jobs:  # what control.persistence._open_job makes of it
            assert job["kind"] == "vehicle.park"
            self.park_jobs.append(job)
            serial = self.serials[job["vehicle"] - 1]
            station = job["station"]
            number = len(self.park_jobs)
            self.orders.append(
                ActiveOrder(
                    transport_order_id=-(2 * number + 1),
                    vda_order_id=f"move-{number}",
                    vehicle_pk=job["vehicle"],
                    route=shortest(self.vehicles[serial].last_node_id, LAYOUT.parking[station]),
                    pickup_node=LAYOUT.parking[station],
                    map_id="hall",
                    pick_station=station,
                    drop_station=station,
                    kind="park",
                )
            )


@pytest.mark.parametrize("idle_at", ["W5", "W4"])  # on the goal; in the one-lane passage
def test_without_parking_the_order_never_starts(idle_at: str) -> None:
    world = World({"AGV-1": "W1", "AGV-2": idle_at}, park_idle=False)
    world.transport("AGV-1", "W3", "W5")

    world.run(60.0)

    assert world.finished == set()
    assert world.vehicles["AGV-1"].last_node_id == "W1"
    assert world.controller.fleet.vehicles[("sim", "AGV-1")].execution is None
    assert world.park_jobs == []
    assert world.controller.traffic is not None
    assert any("no plan for TO-1" in p for p in world.controller.traffic.problems)


@pytest.mark.parametrize("idle_at", ["W5", "W4"])
def test_the_idle_vehicle_parks_and_the_order_finishes(idle_at: str) -> None:
    world = World({"AGV-1": "W1", "AGV-2": idle_at}, park_idle=True)
    world.transport("AGV-1", "W3", "W5")

    world.run(120.0)

    assert 1 in world.finished
    assert world.vehicles["AGV-1"].last_node_id == "W5"
    # Sent once (not again at every failed plan), to the nearest free station: PK2, off W4.
    assert [(j["vehicle"], j["station"]) for j in world.park_jobs] == [(2, "PARK-2")]
    assert world.park_jobs[0]["reason"] == "in the way of order TO-1"
    assert world.vehicles["AGV-2"].last_node_id == "PK2"
    assert -3 in world.finished  # the move to the park station finished too
    assert world.checker.count == 0
    assert world.checker.steps > 100


def test_a_vehicle_left_on_a_station_after_its_order_is_parked_for_the_next() -> None:
    """AGV-2 ends its order on W5; AGV-1's later order to W5 gets it out of the way."""
    world = World({"AGV-1": "W1", "AGV-2": "W4"}, park_idle=True)
    world.transport("AGV-2", "W4", "W5")
    world.run(60.0)
    assert world.finished == {1}
    assert world.vehicles["AGV-2"].last_node_id == "W5"

    world.transport("AGV-1", "W2", "W5")
    world.run(120.0)

    assert 2 in world.finished
    assert [j["vehicle"] for j in world.park_jobs] == [2]
    assert world.vehicles["AGV-2"].last_node_id in {"PK1", "PK2"}
    assert world.checker.count == 0


def test_two_vehicles_each_on_the_other_s_goal_are_not_stuck_for_good(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """AGV-1's order ends where AGV-2 stands and AGV-2's where AGV-1 stands (both left on a
    station by their last order and given the next): neither finds a plan, and neither leaves
    by itself. Once stuck longer than WAITING_FOR, one is sent to park and both finish."""
    monkeypatch.setattr(parking, "WAITING_FOR", 0.5)  # seconds of control's (real) clock
    world = Redispatching({"AGV-1": "W1", "AGV-2": "W5"}, park_idle=True)
    world.transport("AGV-1", "W3", "W5")
    world.transport("AGV-2", "W3", "W1")
    traffic = world.controller.traffic
    assert traffic is not None
    assert traffic.parking is not None
    for name in ("sim/AGV-1", "sim/AGV-2"):  # both orders found no plan a moment ago
        traffic.parking.failed(name, time.monotonic())

    deadline = time.monotonic() + 30.0
    while not {1, 2} <= world.finished and time.monotonic() < deadline:
        world.run(2.0)
        time.sleep(0.05)

    assert {1, 2} <= world.finished
    assert world.park_jobs  # what broke the wait
    assert world.vehicles["AGV-1"].last_node_id == "W5"
    assert world.vehicles["AGV-2"].last_node_id == "W1"
    assert world.checker.count == 0


class Redispatching(World):
    """A transport order requeued because its vehicle left the route's start (it was parked)
    gets a new route from where the vehicle stands, as dispatch would give it."""

    def collect(self) -> None:
        batch = self.controller.collect_flush()
        self.finished |= {p.order_id for p in batch.progress if p.kind == "finished"}
        assert [p for p in batch.progress if p.kind == "failed"] == []
        for progress in batch.progress:
            if progress.kind == "requeued":
                self._reroute(progress.order_id)
        self.take_jobs(batch.job_requests)

    def _reroute(self, order_id: int) -> None:
        i, order = next(
            (i, o) for i, o in enumerate(self.orders) if o.transport_order_id == order_id
        )
        here = self.vehicles[self.serials[order.vehicle_pk - 1]].last_node_id
        pickup, drop = order.pickup_node, order.route[-1]
        route = shortest(here, pickup)[:-1] + shortest(pickup, drop)
        self.orders[i] = dataclasses.replace(order, route=route)
        # dispatch took it back: one read of the active orders does not list it
        rest = [o for o in self.orders if o.transport_order_id not in self.finished | {order_id}]
        self.controller.sync(rest)


def test_a_vehicle_idle_off_a_park_station_goes_to_park_after_a_while(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """With `park_after`, AGV-2 left on W5 by its order is parked unasked; AGV-1 standing on
    W1 with an order assigned (not yet started) is not."""
    world = World({"AGV-1": "W1", "AGV-2": "W4"}, park_idle=True)
    traffic = world.controller.traffic
    assert traffic is not None
    assert traffic.parking is not None
    traffic.parking.park_after = 0.3  # seconds of control's (real) clock
    world.transport("AGV-2", "W4", "W5")
    world.run(60.0)
    assert world.finished == {1}
    assert world.park_jobs == []  # not yet: it has only just finished

    time.sleep(0.4)
    busy = {1}  # AGV-1 (pk 1) has an order assigned
    traffic.park_stale(busy, time.monotonic())  # the first look: AGV-2 idle from now
    time.sleep(0.4)
    traffic.park_stale(busy, time.monotonic())
    world.collect()

    assert [(j["vehicle"], j["station"]) for j in world.park_jobs] == [(2, "PARK-2")]
    assert world.park_jobs[0]["reason"].startswith("idle for")
    for _ in range(300):  # (run() returns at once: every transport order finished)
        world.run(0.1)
    assert world.vehicles["AGV-2"].last_node_id == "PK2"
    assert world.checker.count == 0
    traffic.park_stale(set(), time.monotonic() + 60.0)  # parked: never sent again
    world.collect()
    assert len(world.park_jobs) == 2  # AGV-1 (idle off a station, no order now) goes too
    assert world.park_jobs[1]["vehicle"] == 1
