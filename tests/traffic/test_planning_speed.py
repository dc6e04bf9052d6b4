"""The planning shortcuts (shared safe intervals, bounded first search) change nothing unsafe."""

from tests.traffic.helpers import ListTasks, manager
from tests.traffic.test_adg import waiting_pair
from tests.traffic.test_sipp import overlaps
from traffic.des import SimConfig, Simulation
from traffic.layout import Layout
from traffic.manager import TrafficManager
from traffic.plans import Goal


def busy_grid(**options: object) -> tuple[TrafficManager, Simulation, ListTasks]:
    layout = Layout.grid({(r, c) for r in range(5) for c in range(6)})
    starts = {f"v{i}": f"{r},0" for i, r in enumerate(range(5))}
    goals = {
        f"v{i}": [[Goal(f"{4 - r},5", 2.0)], [Goal(f"{r},1")], [Goal(f"{(r + 2) % 5},4")]]
        for i, r in enumerate(range(5))
    }
    m = manager(layout, starts, **options)
    tasks = ListTasks(goals)
    config = SimConfig(delay_probability=0.3, delay_range=(1.0, 8.0), partial=True, seed=3)
    return m, Simulation(m, tasks, config), tasks


def test_cached_safe_intervals_match_a_fresh_computation_throughout_a_run() -> None:
    m, sim, _ = busy_grid()
    table = m.table
    checked = 0
    for until in range(5, 400, 5):  # re-timing, releases, clearing and re-plans in between
        sim.run(float(until))
        for r in range(m.layout.resource_count):
            for vehicle in (-1, *range(5)):
                shared = table.safe_intervals(r, vehicle)
                assert shared == table._between(r, vehicle), (until, r, vehicle)
                checked += 1
    assert checked > 0
    assert len(table._gaps) > 0  # the cache was in use


def test_a_bounded_first_search_falls_back_and_stays_collision_free() -> None:
    m, sim, tasks = busy_grid(quick_search=(1, 2.0))  # every first search gives up at once
    stats = sim.run(2000.0)
    assert sum(tasks.done.values()) == 15
    assert stats.collisions == 0
    assert stats.wait_cycles == 0
    assert stats.stalls == 0


def test_the_fallback_plan_is_valid_and_within_its_weight() -> None:
    layout = Layout.grid({(r, c) for r in range(8) for c in range(12)})
    exact = manager(layout, {"a": "0,0", "b": "7,11"})
    bounded = manager(layout, {"a": "0,0", "b": "7,11"}, quick_search=(1, 2.0))
    for m in (exact, bounded):
        m.plan("b", "0,11", 0.0)
    best = exact.plan("a", "7,11", 0.0).arrive[-1]
    assert best <= bounded.plan("a", "7,11", 0.0).arrive[-1] <= 2.0 * best
    assert overlaps(bounded) == []


def test_a_stall_report_names_the_wait_for_chain_down_to_its_root() -> None:
    m = waiting_pair()  # b waits for a; a has its whole route released and stands at its start
    sim = Simulation(m, ListTasks({}), SimConfig(delay_probability=0.0))
    chain = sim._watch.describe_chain(sim._by_name["b"], 0.0)
    b_line, a_line = chain.split(" | ")[1:]
    assert b_line.startswith("b at 1,3")
    assert "blocked_by 0" in b_line
    assert "v0 " in b_line  # a's hold queued ahead of b's next step
    assert a_line.startswith("a at 0,0")
    assert "ahead []" in a_line
    m.on_progress("a", 6, 10.0)  # a at the end of its route: the root line must still render
    assert "a at 0,6" in sim._watch.describe_chain(sim._by_name["a"], 10.0)
