"""Which park station an idle vehicle in the way gets (control/parking.py), without vehicles.

`choose_station` is pure; `IdleParking.unavailable` reads a real `TrafficManager`'s holds.
"""

import math

from control.execution import LayoutIndex, NodePlace
from control.parking import (
    PARK_EVERY,
    IdleParking,
    choose_station,
    free_flow_route,
    nearest,
)
from control.traffic_support import DEFAULT_CLASS, layout_of
from traffic import Goal, TrafficManager

STATIONS = {"P-A": "a", "P-B": "b", "P-C": "c"}
SECONDS = {"a": 10.0, "b": 4.0, "c": 7.0}


def test_the_nearest_free_station_is_chosen() -> None:
    assert choose_station(STATIONS, SECONDS, set()) == "P-B"


def test_unavailable_stations_are_skipped_even_when_nearer() -> None:
    assert choose_station(STATIONS, SECONDS, {"b"}) == "P-C"
    assert choose_station(STATIONS, SECONDS, {"b", "c"}) == "P-A"


def test_unreachable_stations_are_skipped_and_none_may_be_left() -> None:
    seconds = {"a": math.inf, "b": math.inf, "c": 3.0}
    assert choose_station(STATIONS, seconds, set()) == "P-C"
    assert choose_station(STATIONS, seconds, {"c"}) is None
    assert choose_station({}, SECONDS, set()) is None


def test_a_tie_goes_to_the_smaller_station_id() -> None:
    assert choose_station({"P-2": "b", "P-1": "c"}, {"b": 5.0, "c": 5.0}, set()) == "P-1"


def spurs() -> LayoutIndex:
    """W1 … W6 in a row, 2 m apart; park spurs K2 … K5 above W2 … W5."""
    nodes = {f"W{i}": NodePlace(2.0 * i, 0.0, None, "m") for i in range(1, 7)}
    nodes |= {f"K{i}": NodePlace(2.0 * i, 2.0, None, "m") for i in range(2, 6)}
    pairs = [(f"W{i}", f"W{i + 1}") for i in range(1, 6)]
    pairs += [(f"W{i}", f"K{i}") for i in range(2, 6)]
    edges = {}
    for a, b in pairs:
        edges[(a, b)], edges[(b, a)] = f"{a}-{b}", f"{b}-{a}"
    return LayoutIndex("m", nodes, edges, parking={f"PARK-{i}": f"K{i}" for i in range(2, 6)})


def test_the_free_flow_route_is_the_shortest_way_through_the_goals() -> None:
    index = spurs()
    manager = TrafficManager(layout_of(index), (DEFAULT_CLASS,))
    layout = manager.layout
    graph = manager.graphs[0]

    steps = free_flow_route(graph, layout.node("W1"), [layout.node("K3"), layout.node("W6")])

    assert [layout.node_ids[n] for _, n in steps] == ["W2", "W3", "K3", "W3", "W4", "W5", "W6"]
    assert all(segment >= layout.node_count for segment, _ in steps)  # segment resources
    assert free_flow_route(graph, layout.node("W1"), [layout.node("W1")]) == []


def test_held_reserved_targeted_and_on_the_way_stations_are_unavailable() -> None:
    index = spurs()
    manager = TrafficManager(layout_of(index), (DEFAULT_CLASS,))
    layout = manager.layout
    manager.add_vehicle("holder", "K2", 0.0)  # stands on K2
    manager.add_vehicle("driver", "W6", 0.0)
    manager.plan("driver", [Goal("K4", 0.0)], 0.0)  # reserves K4 (and its way there)
    parking = IdleParking(lambda job: None)
    parking.sent["earlier"] = (100.0, "K3")  # asked to park on K3 just now
    parking.sent["long ago"] = (100.0 - PARK_EVERY - 1, "K5")  # an old request no longer counts
    way = free_flow_route(manager.graphs[0], layout.node("W1"), [layout.node("W2")])

    taken = parking.unavailable(manager, index, {}, way, 100.0)

    assert taken == {"W2", "K2", "K3", "K4"}
    seconds = {"K2": 1.0, "K3": 2.0, "K4": 3.0, "K5": 9.0}
    assert choose_station(index.parking, seconds, taken) == "PARK-5"


def test_the_nearest_station_is_found_without_passing_the_waiting_vehicle() -> None:
    index = spurs()
    manager = TrafficManager(layout_of(index), (DEFAULT_CLASS,))
    layout, graph = manager.layout, manager.graphs[0]
    node = layout.node
    stations = {node(n) for n in index.parking.values()}
    waiting_at = set(manager.conflicts.of(0, node("W3")))  # the order's vehicle stands there

    # From W4: K4 is next to it; without K4, K3 (past W3) and K5 are as near.
    assert nearest(graph, node("W4"), stations) == {node("K4"): 2.0}
    assert nearest(graph, node("W4"), stations - {node("K4")}) == {node("K3"): 4.0, node("K5"): 4.0}
    assert nearest(graph, node("W4"), stations - {node("K4")}, waiting_at) == {node("K5"): 4.0}
    assert nearest(graph, node("W4"), {node("K2")}, waiting_at) == {}  # only past the vehicle
