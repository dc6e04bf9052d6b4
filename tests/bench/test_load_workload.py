"""The load benchmark's layout and order streams (pure logic, no processes)."""

import itertools
import math
import random

from bench.load.probes import ZONE, _workload
from bench.load.setup import layout_spec


def _coordinates(station: str) -> tuple[int, int]:
    _, column, row = station.split("-")
    return int(column), int(row)


def test_shelves_add_one_handover_spur_per_aisle_node_clear_of_the_park_spurs() -> None:
    plain, shelved = layout_spec(50), layout_spec(50, shelves=True)
    aisles = [n for n in shelved["nodes"] if n["id"].startswith("A")]
    shelves = [s for s in shelved["stations"] if s["kind"] == "HANDOVER"]
    assert not [s for s in plain["stations"] if s["kind"] == "HANDOVER"]
    assert len(shelves) == len(aisles)
    spurs = [n for n in shelved["nodes"] if n["id"].startswith("S-")]
    closest = min(
        math.dist((a["x"], a["y"]), (b["x"], b["y"])) for a, b in itertools.combinations(spurs, 2)
    )
    assert closest >= 2.0  # a 1.2 x 0.8 m vehicle on each spur does not touch its neighbour


def test_zone_orders_pick_and_drop_at_two_shelves_near_the_vehicles_home() -> None:
    layout = layout_spec(200, shelves=True)
    homes = [s["id"] for s in layout["stations"] if s["kind"] == "PARK"]
    next_steps = _workload("zone", layout, random.Random(1))
    for home in homes:
        pick, drop = next_steps(home)
        assert (pick["operation"], drop["operation"]) == ("PICK", "DROP")
        assert pick["station"] != drop["station"]
        column, row = _coordinates(home)
        for step in (pick, drop):
            assert step["station"].startswith("SHELF-")
            c, r = _coordinates(step["station"])
            assert abs(c - column) <= ZONE
            assert abs(r - row) <= ZONE


def test_cross_orders_pick_on_the_top_row_and_drop_on_the_bottom_row() -> None:
    layout = layout_spec(200)
    pick, drop = _workload("cross", layout, random.Random(1))("PARK-000-000")
    assert pick["station"].startswith("PICK-")
    assert drop["station"].startswith("DROP-")
