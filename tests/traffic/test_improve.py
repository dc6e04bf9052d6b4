"""Opt-in lifelong helpers for S2: re-planning late vehicles (`TrafficManager(improve_budget)`)
and trying a task's plan again on the way (`SimConfig(retry_on_the_way)`)."""

from tests.traffic.helpers import ListTasks, cells, manager
from tests.traffic.test_adg import released_conflicts
from traffic.des import SimConfig, Simulation
from traffic.layout import Layout
from traffic.plans import Goal, ReleasePolicy

OPEN = Layout.grid(cells(["........", "........", "........"]))
# a lane with two dead-end pockets:   . . . . . . .
#                                     @ . @ . @ @ @
LANE = Layout.grid(cells([".......", "@.@.@@@"]))
ONE_STEP = ReleasePolicy(max_steps=1, max_distance=1.0)


def _late_b(improve_budget: int) -> float:
    """a drives along row 0, b (planned after it) waits at 1,4 for a to pass 0,4; then a's
    plan is cut short at its decision point. Returns b's planned arrival at 0,4 after a tick."""
    m = manager(OPEN, {"a": "0,0", "b": "2,4"}, policy=ONE_STEP, improve_budget=improve_budget)
    m.plan("a", "0,7", 0.0)
    before = m.plan_of("b")
    plan = m.plan("b", "0,4", 0.0)
    assert plan.nodes == ("2,4", "1,4", "0,4")
    assert plan.arrive[-1] > 5.0  # waits for a (alone: 3 s, a turn and two moves)
    assert before.nodes == ("2,4",)
    m.plan("a", "0,1", 0.0)  # a stops at its decision point: row 0 is free
    m.tick(0.5)
    assert released_conflicts(m) == []
    return m.plan_of("b").arrive[-1]


def test_a_late_vehicle_is_re_planned_when_its_wait_opened_up() -> None:
    assert _late_b(0) > 5.0  # only waiting vehicles are re-planned: b drives, its plan stays
    assert _late_b(1) == 3.5  # re-planned at 0.5 s: 2 s to its decision point, 1 s on


def _task_done(retry_on_the_way: bool) -> float:
    """a stands at the start of a route that does not serve its task (to 0,6, its first step
    released); its task is 1,3."""
    m = manager(LANE, {"a": "0,0"}, policy=ONE_STEP)
    source = ListTasks({"a": []})
    sim = Simulation(m, source, SimConfig(delay_probability=0.0, retry_on_the_way=retry_on_the_way))
    sim.run(0.001)
    plan = m.plan("a", "0,6", sim.now)
    car = sim._cars[0]
    car.goals = [Goal("1,3")]
    assert plan.base_end == 1
    sim._settle(car)  # it stands mid-route (as at a decision point): drive on, or plan the task
    stats = sim.run(60.0)
    assert source.done["a"] == 1
    assert stats.collisions == 0
    return stats.tasks[0].done


def test_a_vehicle_on_another_route_plans_its_task_on_the_way() -> None:
    without, on_the_way = _task_done(False), _task_done(True)
    assert on_the_way < without
    assert on_the_way < 5.01  # planned at 0,0: three moves east, a turn, one move south
