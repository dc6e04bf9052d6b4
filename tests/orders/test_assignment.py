"""The batch assignment on plain graphs: no database."""

from datetime import UTC, datetime, timedelta

from orders.assignment import Candidate, Job, plan_batch, plan_greedy, urgency_key
from traffic import RoutingGraph, VehicleProfile
from traffic.routing import GraphEdge

NOW = datetime(2026, 11, 23, 8, 0, tzinfo=UTC)


def line(n: int = 10, one_way: bool = False) -> RoutingGraph:
    """n0 - n1 - ... with 1 m edges (both ways unless one_way)."""
    nodes = [f"n{i}" for i in range(n)]
    edges = []
    for a, b in zip(nodes, nodes[1:], strict=False):
        edges.append(GraphEdge(f"{a}-{b}", a, b, 1.0))
        if not one_way:
            edges.append(GraphEdge(f"{b}-{a}", b, a, 1.0))
    return RoutingGraph(nodes, edges)


def job(key: int, pickup: str, **kwargs) -> Job:
    kwargs.setdefault("created", NOW - timedelta(minutes=10) + timedelta(seconds=key))
    return Job(key=key, pickup=pickup, station=f"S{key}", **kwargs)


def pairs(plan) -> dict[int, int]:
    return {j.key: v.key for j, v, _ in plan.pairs}


def test_batch_minimises_empty_travel_where_greedy_does_not() -> None:
    graph = line()
    jobs = [job(1, "n4"), job(2, "n6")]
    vehicles = [Candidate(10, "n0"), Candidate(11, "n5")]

    greedy = plan_greedy(jobs, vehicles, graph.distances_to)
    batch = plan_batch(jobs, vehicles, graph.distances_to, now=NOW)

    assert pairs(greedy) == {1: 11, 2: 10}
    assert greedy.empty_travel == 7.0
    assert pairs(batch) == {1: 10, 2: 11}
    assert batch.empty_travel == 5.0


def test_higher_priority_wins_the_contested_near_vehicle() -> None:
    graph = line()
    low, high = job(1, "n5"), job(2, "n4", priority=5)
    vehicles = [Candidate(10, "n0"), Candidate(11, "n5")]

    plan = plan_batch([low, high], vehicles, graph.distances_to, now=NOW)

    assert pairs(plan) == {2: 11, 1: 10}


def test_only_as_many_orders_as_vehicles_enter_a_cycle_most_urgent_first() -> None:
    graph = line()
    jobs = [job(1, "n1"), job(2, "n2", priority=3), job(3, "n3")]

    plan = plan_batch(jobs, [Candidate(10, "n9")], graph.distances_to, now=NOW)

    assert pairs(plan) == {2: 10}
    assert set(plan.notes) == {1, 3}
    assert "waiting for a free vehicle" in plan.notes[1]


def test_an_unreachable_order_takes_no_place_and_says_why() -> None:
    graph = line(one_way=True)  # vehicles can only drive towards higher numbers
    urgent_behind = job(1, "n2", priority=9)
    reachable = job(2, "n8")

    plan = plan_batch([urgent_behind, reachable], [Candidate(10, "n5")], graph.distances_to)

    assert pairs(plan) == {2: 10}
    assert plan.notes == {1: "no vehicle can reach S1"}


def test_a_free_vehicle_left_over_takes_the_next_order() -> None:
    graph = line(one_way=True)
    # Vehicle 10 (n0) can reach both; vehicle 11 (n7) only job 3. Jobs 1 and 2 are more urgent.
    jobs = [job(1, "n2", priority=2), job(2, "n3", priority=1), job(3, "n8")]
    vehicles = [Candidate(10, "n0"), Candidate(11, "n7")]

    plan = plan_batch(jobs, vehicles, graph.distances_to, now=NOW)

    assert pairs(plan) == {1: 10, 3: 11}
    assert "busy with more urgent orders" in plan.notes[2]


def test_ties_go_to_the_vehicle_idle_the_longest() -> None:
    graph = line()
    recently = Candidate(10, "n3", idle_since=NOW - timedelta(minutes=1))
    long_ago = Candidate(11, "n3", idle_since=NOW - timedelta(hours=1))
    never = Candidate(12, "n3", idle_since=None)

    first = plan_batch([job(1, "n5")], [recently, long_ago], graph.distances_to, now=NOW)
    second = plan_batch([job(1, "n5")], [recently, long_ago, never], graph.distances_to, now=NOW)

    assert pairs(first) == {1: 11}
    assert pairs(second) == {1: 12}


def test_deadline_orders_come_first_among_equal_priority_and_count_double_when_due() -> None:
    graph = line()
    relaxed = job(1, "n5")
    due = job(2, "n4", deadline=NOW + timedelta(minutes=5))
    vehicles = [Candidate(10, "n0"), Candidate(11, "n5")]

    assert sorted([relaxed, due], key=urgency_key) == [due, relaxed]
    assert pairs(plan_batch([relaxed], vehicles[:1], graph.distances_to, now=NOW)) == {1: 10}
    assert pairs(plan_batch([relaxed, due], vehicles, graph.distances_to, now=NOW)) == {
        2: 11,
        1: 10,
    }


def test_no_candidates_means_every_job_waits() -> None:
    plan = plan_batch([job(1, "n1")], [], line().distances_to)

    assert plan.pairs == []
    assert plan.notes == {1: "no vehicle available"}


def test_travel_time_per_vehicle_type_decides_not_distance() -> None:
    graph = line()
    fast = VehicleProfile(vehicle_type="fast", max_speed=3.0)
    slow = VehicleProfile(vehicle_type="slow", max_speed=0.5)
    # The slow vehicle is nearer (2 m = 4 s), the fast one farther (4 m = 1.3 s).
    vehicles = [Candidate(10, "n2", profile=slow), Candidate(11, "n8", profile=fast)]

    by_distance = plan_batch([job(1, "n4")], vehicles, graph.distances_to, now=NOW)
    by_time = plan_batch(
        [job(1, "n4")],
        vehicles,
        graph.travel_times_to,
        now=NOW,
        by_profile=lambda goal, profile: graph.travel_times_to(goal, vehicle=profile),  # type: ignore[arg-type]
    )

    assert pairs(by_distance) == {1: 10}
    assert pairs(by_time) == {1: 11}
    assert by_time.empty_travel < 2.0


def test_a_job_takes_only_its_allowed_vehicles_and_says_so_when_none_is_idle() -> None:
    graph = line()
    vehicles = [Candidate(10, "n4"), Candidate(11, "n9")]
    jobs = [job(1, "n4", allowed=frozenset({11})), job(2, "n5", allowed=frozenset({12}))]

    batch = plan_batch(jobs, vehicles, graph.distances_to, now=NOW)
    greedy = plan_greedy(jobs, vehicles, graph.distances_to)

    assert pairs(batch) == pairs(greedy) == {1: 11}
    assert batch.notes == {2: "waiting: no vehicle allowed to take it is idle"}
