"""Layout validation: each finding, and a clean bill of health for the demo warehouse."""

import pytest

from maps.models import Map
from maps.selectors import validate_layout
from maps.services import create_layout, import_lif
from tests.maps.support import example, lif

pytestmark = pytest.mark.django_db


def findings_of(document: dict, map_id: str = "M1") -> set[tuple[str, str, str]]:
    report = import_lif(source=document, site_id="plant")
    assert report.ok, report.lines()
    return {
        (f.severity, f.code, f.object_id)
        for f in validate_layout(map=Map.objects.get(map_id=map_id))
    }


def two_way(*pairs: tuple[str, str]) -> list[tuple[str, str]]:
    return [edge for a, b in pairs for edge in ((a, b), (b, a))]


AISLE = [("a", 0, 0), ("b", 10, 0), ("c", 20, 0)]


def test_the_demo_warehouse_has_no_findings_at_all(demo_map) -> None:
    assert validate_layout(map=demo_map) == []


def test_unreachable_nodes_dead_ends_one_way_edges_and_stations_off_the_graph() -> None:
    nodes = [*AISLE, ("island", 50, 50), ("source", 0, -10), ("sink", 30, 0)]
    edges = [*two_way(("a", "b"), ("b", "c")), ("source", "a"), ("c", "sink")]

    found = findings_of(lif(nodes, edges, [("S-SINK", ["sink"], "DROP")]))

    assert found == {
        ("error", "unreachable-node", "island"),
        ("error", "unreachable-node", "source"),
        ("error", "dead-end", "sink"),
        ("error", "station-off-graph", "S-SINK"),
        ("warning", "missing-reverse", "source-a"),
        ("warning", "missing-reverse", "c-sink"),
    }


def test_one_way_loops_need_no_reverse_edges() -> None:
    loop = [("a", "b"), ("b", "c"), ("c", "a")]

    assert findings_of(lif(AISLE, loop)) == set()


def test_nodes_at_the_same_place_not_joined_by_an_edge_overlap() -> None:
    nodes = [*AISLE, ("b2", 10.01, 0.0), ("c2", 20.0, 0.01)]
    edges = two_way(("a", "b"), ("b", "c"), ("a", "b2"), ("c", "c2"))  # c2 is joined to c

    assert findings_of(lif(nodes, edges)) == {("warning", "overlapping-nodes", "b2")}


def test_a_vehicle_type_that_can_drive_to_a_station_but_not_away_is_reported() -> None:
    nodes = [("a", 0, 0), ("b", 10, 0), ("s", 10, 3)]
    both = ["AGV", "FORK"]
    document = lif(
        nodes,
        [*two_way(("a", "b")), ("b", "s"), ("s", "b")],
        [("PICK-1", ["s"], "PICK")],
        types={"a": both, "b": both, "s": both, "a-b": both, "b-a": both, "b-s": both},
    )

    assert findings_of(document) == {("warning", "vehicle-type-cannot-reach-station", "PICK-1")}


@pytest.mark.parametrize(
    ("kind", "code"),
    [("PICK", "station-on-aisle"), ("CHARGE", "charger-on-aisle"), ("PARK", "parking-on-aisle")],
)
def test_stations_chargers_and_parking_in_a_through_aisle_are_warned_about(kind, code) -> None:
    document = lif(AISLE, two_way(("a", "b"), ("b", "c")), [("S1", ["b"], kind)])

    assert findings_of(document) == {("warning", code, "S1")}


def test_a_trajectory_away_from_its_nodes_is_warned_about() -> None:
    found = findings_of(example("10.17_"), map_id="Map_Z-Level_1")

    assert ("warning", "trajectory-mismatch", "N1-N2") in found


def test_the_same_node_id_on_two_maps_of_a_site_is_an_error() -> None:
    def spec(map_id: str) -> dict:
        return {
            "mapId": map_id,
            "site": "plant",
            "nodes": [{"id": "x", "x": 0, "y": 0}],
            "edges": [],
        }

    create_layout(spec=spec("first"))
    create_layout(spec=spec("second"))

    codes = {f.code for f in validate_layout(map=Map.objects.get(map_id="first"))}

    assert "duplicate-node-id" in codes


def test_a_map_without_nodes_is_warned_about() -> None:
    empty = Map.objects.create(map_id="empty", name="empty")

    assert [f.code for f in validate_layout(map=empty)] == ["empty-map"]


def test_errors_come_first() -> None:
    nodes = [*AISLE, ("sink", 30, 0)]
    report = import_lif(
        source=lif(nodes, [*two_way(("a", "b"), ("b", "c")), ("c", "sink")], [("S", ["b"], "PICK")])
    )
    assert report.ok

    severities = [f.severity for f in validate_layout(map=Map.objects.get(map_id="M1"))]

    assert severities == sorted(severities, key=["error", "warning"].index)
    assert severities[0] == "error"
