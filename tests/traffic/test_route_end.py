"""A re-plan that serves the last goal where the vehicle stands ends its route there.

The S1 stall of the fourth round: a vehicle's plan passed its goal, stepped aside (to let another
vehicle through) and came back. Waiting at the goal for the step-aside cell, it was re-planned by
`tick()` after the vehicle it had stepped aside for took another route: the best plan was now to
stay, so its route ended at its decision point. Nobody was told, and it stood there for good with
its task unfinished. The manager now returns a release with `base_end == route_end` for it, and
the discrete-event run finishes the task when it gets one.
"""

from tests.traffic.helpers import ListTasks, manager
from traffic.des import SimConfig, Simulation
from traffic.layout import Layout
from traffic.manager import TrafficManager
from traffic.plans import Goal, ReleasePolicy

# a corridor 0,0..0,8; its goal 0,2 has a step-aside cell 1,2 below, which b crosses from 1,3
# to 2,2; d drives the corridor from 0,8 to 0,1, through the goal
CELLS = [(0, c) for c in range(9)] + [(1, 2), (1, 3), (2, 2)]
GOAL = "0,2"
TASKS = {"d": [[Goal("0,1")]], "b": [[Goal("2,2")]], "a": [[Goal(GOAL, 5.0)]]}


def corridor() -> TrafficManager:
    """d, b and a standing where their tasks start; short bases, so plans stay revisable."""
    starts = {"d": "0,8", "b": "1,3", "a": "0,0"}
    return manager(Layout.grid(CELLS), starts, policy=ReleasePolicy(max_steps=2, max_distance=2))


def test_a_replan_that_serves_the_last_goal_at_the_decision_point_says_the_route_ends() -> None:
    m = corridor()
    for name, tasks in TASKS.items():
        m.plan(name, tasks[0], 0.0)
    # a must pass 0,1 before d holds it for good: it reaches its goal first, steps aside to
    # 1,2 once b has crossed it, lets d pass, and comes back
    assert m.plan_of("a").nodes == ("0,0", "0,1", GOAL, "1,2", GOAL)
    m.on_progress("a", 1, 1.0)
    m.on_progress("a", 2, 2.0)
    assert m.waiting_for("a") == ["b"]  # b is late: it has not reported 1,2 yet
    m.plan("d", m.plan_of("d").nodes[m.release_of("d").base_end], 3.0)  # d's order changed

    releases = m.tick(8.0)  # a has waited 5 s: re-planned, it stays at its goal

    a = m.vehicle("a")
    assert m.plan_of("a").nodes == ("0,0", "0,1", GOAL)
    assert a.passed == a.base == a.stops[-1] == 2
    assert [r for r in releases if r.vehicle_id == "a"] == [m.release_of("a")]
    assert m.release_of("a").route_end == 2  # the order ends where it stands


def test_the_simulation_finishes_a_task_whose_route_a_replan_ended() -> None:
    m = corridor()
    tasks = ListTasks(TASKS)
    # seed 1: b's first move, and no other before t = 60, is delayed by 30 s
    config = SimConfig(delay_probability=0.1, delay_range=(30.0, 30.0), seed=1)
    sim = Simulation(m, tasks, config)
    sim.run(3.0)
    assert m.plan_of("a").nodes == ("0,0", "0,1", GOAL, "1,2", GOAL)
    assert m.waiting_for("a") == ["b"]
    assert sim.stats.delays == 1
    m.plan("d", m.plan_of("d").nodes[m.release_of("d").base_end], 3.0)  # d's order changed

    stats = sim.run(60.0)

    done = {t.vehicle_id: t.done for t in stats.tasks}
    assert done["a"] == 7.0  # at its goal since 2 s, re-planned at 7 s; b still crossing
    assert tasks.done["a"] == 1
    assert m.plan_of("a").nodes == ("0,0", "0,1", GOAL)
    assert stats.collisions == 0


def test_without_replans_to_the_base_the_old_route_is_kept() -> None:
    # control's setting: the goal's actions are on the later visit of the goal in the order
    starts = {"d": "0,8", "b": "1,3", "a": "0,0"}
    policy = ReleasePolicy(max_steps=2, max_distance=2)
    m = manager(Layout.grid(CELLS), starts, policy=policy, replan_to_base=False)
    for name, tasks in TASKS.items():
        m.plan(name, tasks[0], 0.0)
    m.on_progress("a", 1, 1.0)
    m.on_progress("a", 2, 2.0)
    m.plan("d", m.plan_of("d").nodes[m.release_of("d").base_end], 3.0)

    releases = m.tick(8.0)

    assert m.plan_of("a").nodes == ("0,0", "0,1", GOAL, "1,2", GOAL)
    assert m.vehicle("a").stops[-1] == 4
    assert [r for r in releases if r.vehicle_id == "a"] == []
