"""Opt-in lifelong mechanisms (`traffic.aside`): stepping aside, goal refuges, `proceed`."""

import math

import pytest

from tests.traffic.helpers import AMR, ListTasks, cells, manager
from tests.traffic.test_adg import released_conflicts
from traffic.des import SimConfig, Simulation
from traffic.layout import Layout
from traffic.manager import NoPlanError, TrafficManager
from traffic.plans import Goal, ReleasePolicy

# a lane with two dead-end pockets:   . . . . . . .
#                                     @ . @ . @ @ @
LANE = Layout.grid(cells([".......", "@.@.@@@"]))


def test_without_stepping_aside_a_goal_held_for_good_fails() -> None:
    m = manager(LANE, {"a": "0,0", "p": "0,3"})
    with pytest.raises(NoPlanError):
        m.plan("a", "0,3", 0.0)


def test_a_vehicle_standing_on_the_goal_steps_aside_off_the_route() -> None:
    m = manager(LANE, {"a": "0,0", "p": "0,3"}, step_aside=True)
    plan = m.plan("a", "0,3", 0.0)
    assert plan.complete
    assert plan.nodes[-1] == "0,3"
    moved = [r for r in plan.releases if r.vehicle_id == "p"]
    assert moved
    assert moved[0].base_end >= 1  # p drives off at once
    aside = m.plan_of("p").nodes
    assert aside[0] == "0,3"
    assert aside[-1] not in {"0,0", "0,1", "0,2", "0,3"}  # off a's route
    assert released_conflicts(m) == []


def test_stepping_aside_executes_without_collision() -> None:
    m = manager(LANE, {"a": "0,0", "p": "0,3"}, step_aside=True)
    source = ListTasks({"a": [[Goal("0,3")], [Goal("1,1")]]})
    stats = Simulation(m, source, SimConfig(delay_probability=0.0)).run(120.0)
    assert source.done["a"] == 2
    assert stats.collisions == 0
    assert stats.wait_cycles == 0
    assert m.wait_cycles() == []


def test_a_refuge_plan_visits_the_goal_and_ends_where_it_may_stay() -> None:
    # a refuge on a busy node costs up to 50 s: from the lane's middle, the pocket is better
    m = manager(LANE, {"a": "0,0"}, goal_refuge=True, refuge_penalty=50.0)
    plan = m.plan("a", "0,3", 0.0)
    assert plan.nodes[plan.stops[0]] == "0,3"
    assert plan.stops == (3,)
    assert plan.nodes[-1] == "1,3"  # the dead end next to the goal
    assert plan.base_end <= 3  # the base stops at the goal


def test_the_base_stops_at_the_goal_until_the_next_plan_or_proceed() -> None:
    m = manager(LANE, {"a": "0,0"}, goal_refuge=True, refuge_penalty=50.0)
    first = m.plan("a", "0,3", 0.0)
    for i in range(1, 4):
        m.on_progress("a", i, float(i))
    assert m.release_of("a").base_end == 3
    assert m.held_at_goal("a")
    nxt = m.plan("a", "0,6", 3.0)  # the next task, planned at the goal: a new route
    assert nxt.plan_id == first.plan_id + 1
    assert nxt.nodes[0] == "0,3"
    assert "0,6" in nxt.nodes
    m2 = manager(LANE, {"a": "0,0"}, goal_refuge=True, refuge_penalty=50.0)
    m2.plan("a", "0,3", 0.0)
    for i in range(1, 4):
        m2.on_progress("a", i, float(i))
    releases = m2.proceed("a", 3.0)
    assert [r.base_end for r in releases] == [4]  # on to the refuge
    assert not m2.held_at_goal("a")


def test_a_goal_someone_parks_on_later_can_still_be_visited_with_a_refuge() -> None:
    # b's plan ends on 0,7 for good (it gets there at t = 7); a, next to it, needs one visit
    lane = Layout.grid([(0, c) for c in range(10)])

    def fleet(**options: object) -> TrafficManager:
        short = ReleasePolicy(max_steps=2, max_distance=2.0)  # b's hold on 0,7 is not released
        m = TrafficManager(lane, [AMR], policy=short, **options)  # type: ignore[arg-type]
        m.add_vehicle("b", "0,0", 0.0, heading=0.0)
        m.add_vehicle("a", "0,8", 0.0, heading=math.pi)  # facing the goal
        m.plan("b", "0,7", 0.0)
        return m

    with pytest.raises(NoPlanError):
        fleet().plan("a", "0,7", 0.0)
    m = fleet(goal_refuge=True)
    plan = m.plan("a", "0,7", 0.0)
    assert plan.complete
    assert plan.nodes[plan.stops[0]] == "0,7"
    assert plan.nodes[-1] in {"0,8", "0,9"}  # back out of b's way before it arrives
    assert released_conflicts(m) == []


def test_a_dense_lifelong_run_finishes_its_tasks_safely() -> None:
    grid = Layout.grid(cells(["......", ".@..@.", "......", ".@..@."]))
    starts = {"a": "0,0", "b": "0,5", "c": "2,0", "d": "2,5", "e": "3,2"}
    tasks = {
        "a": [[Goal("2,5")], [Goal("0,0")], [Goal("3,3")]],
        "b": [[Goal("2,0")], [Goal("0,5")], [Goal("0,2")]],
        "c": [[Goal("0,5")], [Goal("3,5")], [Goal("2,2")]],
        "d": [[Goal("0,0")], [Goal("3,0")], [Goal("0,3")]],
        "e": [[Goal("0,3")], [Goal("2,3")], [Goal("3,2")]],
    }
    m = manager(grid, starts, goal_refuge=True, step_aside=True, refuge_penalty=20.0)
    source = ListTasks(tasks)
    config = SimConfig(delay_probability=0.0, partial=True, finish_at_goal=True)
    stats = Simulation(m, source, config).run(400.0)
    assert all(done == 3 for done in source.done.values()), source.done
    assert stats.collisions == 0
    assert stats.wait_cycles == 0
    assert stats.stalls == 0
