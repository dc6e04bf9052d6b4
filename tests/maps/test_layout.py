import math

import pytest

from fleet.exceptions import InvalidRequestError
from maps.demo import warehouse_layout
from maps.models import Edge, Map, Station
from maps.selectors import layout_as_dict, load_graph
from maps.services import create_layout


def test_demo_layout_has_every_station_kind_on_spurs(demo_map) -> None:
    kinds = set(Station.objects.filter(map=demo_map).values_list("kind", flat=True))

    assert kinds == {"PICK", "DROP", "CHARGE", "PARK"}
    for station in Station.objects.filter(map=demo_map):
        assert station.node.outgoing.count() == 1  # a dead-end spur, not a through aisle


def test_every_station_reaches_every_other(demo_map) -> None:
    graph = load_graph(map=demo_map)
    nodes = [s.node.node_id for s in Station.objects.filter(map=demo_map)]

    for start in nodes:
        assert set(nodes) <= graph.distances_to(start).keys()


def test_edge_length_is_the_distance_between_its_nodes(demo_map) -> None:
    for edge in Edge.objects.filter(map=demo_map).select_related("start", "end")[:20]:
        assert edge.length == pytest.approx(
            math.dist((edge.start.x, edge.start.y), (edge.end.x, edge.end.y))
        )


def test_creating_a_map_twice_needs_replace(demo_map) -> None:
    spec = warehouse_layout(columns=6, rows=4)
    with pytest.raises(InvalidRequestError):
        create_layout(spec=spec)

    replaced = create_layout(spec=warehouse_layout(columns=3, rows=3), replace=True)

    assert layout_as_dict(map=replaced)["nodes"][0]["id"] == "A0.0"
    assert replaced.nodes.count() < 30


@pytest.mark.django_db
def test_an_edge_to_an_unknown_node_is_refused_and_nothing_is_written() -> None:
    spec = {
        "mapId": "bad",
        "nodes": [{"id": "a", "x": 0, "y": 0}],
        "edges": [{"id": "e", "start": "a", "end": "missing"}],
    }
    with pytest.raises(InvalidRequestError, match="missing"):
        create_layout(spec=spec)

    assert not Edge.objects.exists()
    assert not Map.objects.filter(map_id="bad").exists()
