"""One-way aisles in the benchmark warehouse (`bench.traffic.maps.warehouse(one_way_aisles=True)`).

The aisles between the shelf rows alternate east and west; the passages between shelf blocks
and the margins stay two-way. The map must stay strongly connected (planning completeness
needs every node to reach every other), and the planner, its fallbacks and stepping aside must
only ever drive the allowed directions.
"""

import random
from collections import deque

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from bench.traffic import __main__ as cli
from bench.traffic import scenarios
from bench.traffic.fleet import WarehouseTasks, fleet_manager, node_id
from bench.traffic.maps import GridMap, warehouse
from tests.traffic.test_adg import released_conflicts
from tests.traffic.test_switching import schedule_breaks
from traffic.des import SimConfig, Simulation
from traffic.layout import Layout
from traffic.manager import TrafficManager
from traffic.plans import ReleasePolicy

Cell = tuple[int, int]

shapes = st.fixed_dictionaries(
    {
        "block_cols": st.integers(1, 5),
        "block_rows": st.integers(1, 6),
        "block_len": st.integers(2, 8),
        "margin": st.integers(1, 5),
        "station_cols": st.integers(1, 2),
    }
)


def shaped(shape: dict[str, int], *, one_way: bool, passages: bool = False) -> GridMap:
    return warehouse(
        block_cols=shape["block_cols"],
        block_rows=shape["block_rows"],
        block_len=shape["block_len"],
        margin=shape["margin"],
        station_cols=shape["station_cols"],
        one_way_aisles=one_way,
        one_way_passages=passages,
    )


def reached(start: int, out: list[list[int]]) -> set[int]:
    seen, todo = {start}, deque([start])
    while todo:
        for w in out[todo.popleft()]:
            if w not in seen:
                seen.add(w)
                todo.append(w)
    return seen


def aisle_rows(block_rows: int) -> list[int]:
    """The rows of the aisles between shelf rows, top first (1-cell aisles, 2-cell shelves)."""
    return [1 + 3 * k for k in range(block_rows + 1)]


def shelf_span(grid: GridMap, margin: int) -> range:
    return range(1 + margin, grid.width - 1 - margin)


@settings(max_examples=80, deadline=None, derandomize=True)
@given(shapes, st.booleans())
def test_one_way_aisles_alternate_and_every_node_reaches_every_other(
    shape: dict[str, int], passages: bool
) -> None:
    """Aisles east, west, east, … (top first); with `passages` the passages between blocks
    down, up, down, … (left first); everything else two-way; strongly connected."""
    grid = shaped(shape, one_way=True, passages=passages)
    plain = shaped(shape, one_way=False)
    assert (grid.free, grid.picks, grid.stations) == (plain.free, plain.picks, plain.stations)
    assert plain.one_way is None
    assert grid.one_way is not None
    layout = Layout.grid(grid.free, parking=grid.stations, one_way=grid.one_way)
    edges = {(layout.node_ids[e.start], layout.node_ids[e.end]) for e in layout.edges}
    out: list[list[int]] = [[] for _ in layout.node_ids]
    back: list[list[int]] = [[] for _ in layout.node_ids]
    for e in layout.edges:
        out[e.start].append(e.end)
        back[e.end].append(e.start)
    everyone = set(range(layout.node_count))
    assert reached(0, out) == everyone  # strongly connected: 0 reaches all, all reach 0
    assert reached(0, back) == everyone
    span = shelf_span(grid, shape["margin"])
    for k, r in enumerate(aisle_rows(shape["block_rows"])):
        east = k % 2 == 0
        for c in span[:-1]:
            forward = (node_id((r, c)), node_id((r, c + 1)))
            backward = (node_id((r, c + 1)), node_id((r, c)))
            assert (forward in edges, backward in edges) == (east, not east)
        # the aisle's ends open to the margins in its direction only
        enter, leave = (span[0] - 1, span[0]) if east else (span[-1] + 1, span[-1])
        assert (node_id((r, enter)), node_id((r, leave))) in edges
        assert (node_id((r, leave)), node_id((r, enter))) not in edges
    pitch = shape["block_len"] + 1
    for (r, c), (r2, c2) in _neighbours(grid.free):
        if c not in span and c2 not in span:
            assert (node_id((r, c)), node_id((r2, c2))) in edges  # margins: two-way
        elif c == c2:  # a step on a passage between blocks
            down = (c - span[0]) // pitch % 2 == 0
            allowed = not passages or (r2 > r) == down
            assert ((node_id((r, c)), node_id((r2, c2))) in edges) == allowed


def test_one_way_passages_need_one_way_aisles() -> None:
    with pytest.raises(ValueError, match="one_way_aisles"):
        warehouse(one_way_passages=True)


def _neighbours(free: frozenset[Cell]) -> list[tuple[Cell, Cell]]:
    return [
        ((r, c), (r + dr, c + dc))
        for r, c in free
        for dr, dc in ((0, 1), (1, 0), (0, -1), (-1, 0))
        if (r + dr, c + dc) in free
    ]


class DirectionChecked(Simulation):
    """Records every move a vehicle starts and checks the ADG invariants on every arrival."""

    moves: set[tuple[int, int]]

    def _occupy(self, car, resources):  # type: ignore[no-untyped-def]
        if len(resources) == 3:  # (from node, segment, to node): a move starts
            self.moves.add((resources[0], resources[2]))
        super()._occupy(car, resources)

    def _arrive(self, car):  # type: ignore[no-untyped-def]
        super()._arrive(car)
        assert released_conflicts(self.manager) == []
        assert schedule_breaks(self.manager) == []


def one_way_fleet(
    seed: int,
    vehicles: int,
    lifelong: bool,
    push: float | None,
    *,
    one_way: bool = True,
    passages: bool = False,
) -> tuple[TrafficManager, WarehouseTasks]:
    """S3's pattern shrunk to 28 x 15 (as `test_switching.small_warehouse`), aisles one way."""
    grid = warehouse(
        block_cols=3,
        block_rows=4,
        block_len=6,
        margin=3,
        station_cols=1,
        one_way_aisles=one_way,
        one_way_passages=passages,
    )
    layout = Layout.grid(grid.free, parking=grid.stations, one_way=grid.one_way)
    chosen = random.Random(seed).sample(sorted(grid.stations), vehicles)
    starts = [(node_id(cell), 0.0) for cell in chosen]
    m = fleet_manager(
        layout,
        starts,
        policy=ReleasePolicy(4, 4.0, 1.0),
        max_expansions=20_000,
        quick_search=(1_000, 1.3),
        lifelong=lifelong,
        switch_push=push,
    )
    tasks = WarehouseTasks(grid, seed, m.vehicle_ids)
    tasks.standing({f"v{i}": node for i, (node, _) in enumerate(starts)})
    return m, tasks


@settings(
    max_examples=20, deadline=None, suppress_health_check=[HealthCheck.too_slow], derandomize=True
)
@given(
    st.integers(0, 10_000),
    st.integers(4, 10),
    st.sampled_from([0.0, 0.05, 0.3]),
    st.booleans(),
    st.sampled_from([None, 10.0]),
    st.booleans(),
)
def test_delayed_fleets_on_one_way_aisles_drive_only_allowed_ways_and_never_collide(
    seed: int,
    vehicles: int,
    delay_probability: float,
    lifelong: bool,
    push: float | None,
    passages: bool,
) -> None:
    """Random fleets with delays, switching and (lifelong) stepping aside: no move against an
    aisle's direction, no collision, no wait-for cycle, no stall, orders done."""
    m, tasks = one_way_fleet(seed, vehicles, lifelong, push, passages=passages)
    config = SimConfig(
        delay_probability=delay_probability,
        seed=seed,
        retry_backoff=2.0,
        reassign_after=3,
        finish_at_goal=lifelong,
    )
    sim = DirectionChecked(m, tasks, config)
    sim.moves = set()
    stats = sim.run(400.0)
    allowed = {(e.start, e.end) for e in m.layout.edges}
    assert sim.moves
    assert sim.moves <= allowed
    assert len(stats.tasks) > 0
    assert (stats.collisions, stats.wait_cycles, stats.stalls) == (0, 0, 0)


def aisle_moves(one_way: bool) -> tuple[set[int], set[int]]:
    """The aisle rows vehicles drove east and west in a delayed 600 s run of 8 vehicles."""
    m, tasks = one_way_fleet(seed=3, vehicles=8, lifelong=False, push=10.0, one_way=one_way)
    sim = DirectionChecked(m, tasks, SimConfig(seed=3, retry_backoff=2.0, reassign_after=3))
    sim.moves = set()
    sim.run(600.0)
    cell = [tuple(map(int, n.split(","))) for n in m.layout.node_ids]
    east: set[int] = set()
    west: set[int] = set()
    for a, b in sim.moves:
        (r, c), (r2, c2) = cell[a], cell[b]
        if r == r2 and (r - 1) % 3 == 0 and 4 <= c <= 23:  # along an aisle, shelf span
            (east if c2 > c else west).add(r)
    return east, west


def test_vehicles_drive_each_aisle_in_its_direction_only_where_it_is_one_way() -> None:
    """Not vacuous: the same delayed run on the two-way map drives some aisle both ways."""
    east, west = aisle_moves(one_way=True)
    assert east
    assert west
    assert east.isdisjoint(west)
    assert all((r - 1) // 3 % 2 == 0 for r in east)
    assert all((r - 1) // 3 % 2 == 1 for r in west)
    east, west = aisle_moves(one_way=False)
    assert east & west


def test_the_command_line_passes_the_one_way_choice_to_s3(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    given: list[object] = []

    def fake_s3(**options: object) -> dict[str, object]:
        given.append(options.get("one_way", "default"))
        return {}

    monkeypatch.setattr(scenarios, "s3", fake_s3)
    for argv in (["--one-way", "all"], ["--one-way", "aisles"], []):
        monkeypatch.setattr("sys.argv", ["bench.traffic", "--scenario", "S3", "--no-write", *argv])
        cli.main()
    assert given == ["all", "aisles", "default"]


def test_s3_refuses_an_unknown_one_way_choice() -> None:
    with pytest.raises(ValueError, match="one_way"):
        scenarios.s3(quick=True, seed=1, one_way="on")
