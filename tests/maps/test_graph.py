"""Routing graphs from the database: vehicle-type rules from LIF, floors, cache invalidation."""

import math

import pytest

from maps.models import Edge, Map, Node, Site, VehicleType
from maps.selectors import load_graph, load_graph_for_routing, load_site_graph, vehicle_profile
from maps.services import import_lif, mark_layout_changed
from tests.maps.support import example
from traffic import NoRouteError

pytestmark = pytest.mark.django_db


def test_the_graph_is_cached_until_the_layout_changes(demo_map) -> None:
    graph = load_graph(map=demo_map)
    graph.travel_times_to("S-PICK-1")  # fills a distance table

    assert load_graph(map=demo_map) is graph

    mark_layout_changed(maps=[demo_map])
    fresh = load_graph(map=demo_map)

    assert fresh is not graph
    assert fresh.for_vehicle()._tables == {}


def test_a_changed_layout_changes_the_routes(demo_map) -> None:
    before = load_graph(map=demo_map).route("A0.0", "A0.3")
    a, b = (
        Node.objects.get(map=demo_map, node_id="A0.0"),
        Node.objects.get(map=demo_map, node_id="A0.3"),
    )
    Edge.objects.create(map=demo_map, edge_id="shortcut", start=a, end=b, length=1.0)

    cached = load_graph(map=demo_map).route("A0.0", "A0.3")
    mark_layout_changed(maps=[demo_map])
    after = load_graph(map=demo_map).route("A0.0", "A0.3")

    assert cached == before  # unchanged until the change is marked (services and admin mark)
    assert after.edges == ["shortcut"]


def test_lif_vehicle_types_restrict_stations_nodes(db) -> None:
    import_lif(source=example("10.8_"), site_id="plant")
    graph = load_graph(map=Map.objects.get())
    type_1 = vehicle_profile(vehicle_type=VehicleType.objects.get(type_id="Vehicle_Type_1"))
    type_2 = vehicle_profile(vehicle_type=VehicleType.objects.get(type_id="Vehicle_Type_2"))

    assert graph.route("N1", "N2", vehicle=type_1).nodes == ["N1", "N2"]
    assert graph.route("N4", "N3", vehicle=type_2).nodes == ["N4", "N3"]
    with pytest.raises(NoRouteError):
        graph.route("N1", "N2", vehicle=type_2)


def test_load_restrictions_from_lif_choose_the_edge_for_the_load(db) -> None:
    import_lif(source=example("10.12_"), site_id="plant")
    graph = load_graph(map=Map.objects.get())
    vehicle_type = VehicleType.objects.get()

    def edges(load_set: str) -> list[str]:
        profile = vehicle_profile(vehicle_type=vehicle_type, loaded=True, load_set=load_set)
        return graph.route("N1", "N0", vehicle=profile).edges

    assert edges("Stable_Load_Unit") == ["N1-N0_Stable_Load"]
    assert edges("Unstable_Load_Unit") == ["N1-N0_Unstable_Load"]


def test_vehicle_type_speeds_price_the_route(db) -> None:
    import_lif(source=example("10.1_"), site_id="plant")
    vehicle_type = VehicleType.objects.get()
    vehicle_type.max_speed, vehicle_type.rotation_speed = 2.0, math.pi
    vehicle_type.save()

    route = load_graph(map=Map.objects.get()).route(
        "N1", "N2", vehicle=vehicle_profile(vehicle_type=vehicle_type)
    )

    assert route.travel_time == pytest.approx(11.0 / 2.0)


def test_maps_without_vehicle_types_stay_open_to_typed_vehicles(demo_map) -> None:
    import_lif(source=example("10.1_"), site_id="plant")  # creates Vehicle_Type_1
    profile = vehicle_profile(vehicle_type=VehicleType.objects.get())

    assert load_graph(map=demo_map).route("A0.0", "A5.3", vehicle=profile).nodes[-1] == "A5.3"


def test_the_site_graph_routes_across_floors_and_a_single_map_does_not(db) -> None:
    import_lif(source=example("10.14_"), site_id="plant")
    ground = Map.objects.get(map_id="Map_Z-Level_1")

    assert load_site_graph(site=Site.objects.get()).route("N1", "N101").nodes == [
        "N1",
        "N2",
        "N102",
        "N101",
    ]
    assert load_graph_for_routing(map=ground).route("N1", "N101").map_ids == [
        "Map_Z-Level_1",
        "Map_Z-Level_2",
    ]
    with pytest.raises(NoRouteError):
        load_graph(map=ground).route("N1", "N101")
