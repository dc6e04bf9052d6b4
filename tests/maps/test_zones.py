"""Zones shape routing: blocked, restricted, speed limit, one-way, penalty; and the cache follows.

The demo map (6 × 4 aisle grid, 3 m apart): aisle node A{c}.{r} at (3c, 3r); pick stations on
spurs 2 m above the top row (S-PICK-c at (3c, 11)), drops 2 m below the bottom row.
"""

import pytest

from maps.models import Map, Station, VehicleType, Zone
from maps.selectors import edge_speed_limits, layout_as_dict, load_graph, validate_layout
from maps.services import (
    ZoneError,
    create_zone,
    delete_zone,
    mark_layout_changed,
    set_zones_enabled,
    update_zone,
)
from maps.zoning import DIRECTED_SOFT_FACTOR
from tests.maps.zones_support import box, positions
from traffic import NoRouteError, VehicleProfile

pytestmark = pytest.mark.django_db


def inside(point: tuple[float, float], x1: float, y1: float, x2: float, y2: float) -> bool:
    return x1 <= point[0] <= x2 and y1 <= point[1] <= y2


def test_a_blocked_zone_is_never_entered_the_route_goes_around_it(demo_map: Map) -> None:
    straight = load_graph(map=demo_map).route("A0.1", "A5.1")
    create_zone(map=demo_map, zone_id="spill", zone_type="BLOCKED", vertices=box(5, 2, 10, 4))

    graph = load_graph(map=demo_map)
    route = graph.route("A0.1", "A5.1")
    path = graph.shortest_path("A0.1", "A5.1")

    assert straight.nodes == ["A0.1", "A1.1", "A2.1", "A3.1", "A4.1", "A5.1"]
    for node_ids in (route.nodes, path):
        assert not any(inside(p, 5, 2, 10, 4) for p in positions(demo_map, node_ids))
    assert route.length == pytest.approx(straight.length + 6.0)  # one row up or down and back
    assert not {"A1.1-A2.1", "A2.0-A2.1", "A4.1-A3.1"} & {e.edge_id for e in graph.edges}


def test_a_station_inside_a_blocked_zone_is_unreachable_and_validation_reports_it(
    demo_map: Map,
) -> None:
    create_zone(map=demo_map, zone_id="Z-pick-2", zone_type="BLOCKED", vertices=box(5, 10, 7, 12))

    graph = load_graph(map=demo_map)
    findings = validate_layout(map=demo_map)

    with pytest.raises(NoRouteError):
        graph.route("A0.0", "S-PICK-2")
    with pytest.raises(NoRouteError):
        graph.shortest_path("A0.0", "S-PICK-2")
    assert [(f.severity, f.code, f.object_id) for f in findings if f.severity == "error"] == [
        ("error", "station-in-blocked-zone", "PICK-2")
    ]
    assert ("info", "node-in-blocked-zone", "S-PICK-2") in {
        (f.severity, f.code, f.object_id) for f in findings
    }


def test_a_vehicle_caught_inside_a_blocked_zone_can_still_leave_it(demo_map: Map) -> None:
    create_zone(map=demo_map, zone_id="Z", zone_type="BLOCKED", vertices=box(5, 10, 7, 12))

    route = load_graph(map=demo_map).route("S-PICK-2", "A0.0")

    assert route.nodes[:2] == ["S-PICK-2", "A2.3"]


def test_a_speed_limit_zone_lowers_the_edge_speed_used_for_travel_time(demo_map: Map) -> None:
    before = load_graph(map=demo_map).route("A1.0", "A3.0").travel_time
    create_zone(
        map=demo_map,
        zone_id="slow",
        zone_type="SPEED_LIMIT",
        vertices=box(2, -0.5, 10, 0.5),
        max_speed=0.5,
    )

    limits = edge_speed_limits(map=demo_map)
    after = load_graph(map=demo_map).route("A1.0", "A3.0").travel_time

    assert before == pytest.approx(6.0)  # 6 m at the default 1 m/s
    assert after == pytest.approx(12.0)  # the zone's 0.5 m/s on both edges
    assert limits["A1.0-A2.0"] == 0.5
    assert limits["A0.0-A1.0"] == 0.5  # partly inside: the limit holds for the whole edge
    assert limits["A4.0-A5.0"] is None  # outside
    assert limits["A0.3-A1.3"] is None


def test_a_speed_zone_keeps_a_lower_limit_of_the_edge_and_of_the_vehicle_type(
    demo_map: Map,
) -> None:
    demo_map.edges.filter(edge_id="A1.0-A2.0").update(max_speed=0.3)
    mark_layout_changed(maps=[demo_map])
    create_zone(
        map=demo_map,
        zone_id="slow",
        zone_type="SPEED_LIMIT",
        vertices=box(2, -0.5, 10, 0.5),
        max_speed=0.5,
    )

    limits = edge_speed_limits(map=demo_map)

    assert limits["A1.0-A2.0"] == 0.3
    assert limits["A2.0-A3.0"] == 0.5


def test_a_one_way_zone_drops_the_edges_against_its_direction(demo_map: Map) -> None:
    create_zone(
        map=demo_map,
        zone_id="east",
        zone_type="DIRECTED",
        vertices=box(1, 2.5, 14, 3.5),
        direction=0.0,
        limitation="RESTRICTED",
    )

    graph = load_graph(map=demo_map)
    westward = graph.route("A4.1", "A1.1")
    eastward = graph.route("A1.1", "A4.1")
    edges = {e.edge_id for e in graph.edges}

    assert eastward.nodes == ["A1.1", "A2.1", "A3.1", "A4.1"]
    assert "A2.1-A1.1" not in edges
    assert {"A1.1-A2.1", "A2.0-A2.1", "A2.1-A2.0"} <= edges  # across the one-way aisle: allowed
    assert not any(
        a[1] == b[1] == 3.0 and b[0] < a[0]
        for a, b in zip(
            positions(demo_map, westward.nodes),
            positions(demo_map, westward.nodes[1:]),
            strict=False,
        )
    )


def test_a_soft_one_way_zone_only_makes_the_wrong_way_costly(demo_map: Map) -> None:
    create_zone(
        map=demo_map,
        zone_id="east",
        zone_type="DIRECTED",
        vertices=box(1, 2.5, 14, 3.5),
        direction=0.0,
        limitation="SOFT",
    )

    graph = load_graph(map=demo_map)
    costs = {e.edge_id: e.cost_factor for e in graph.edges}

    assert costs["A2.1-A1.1"] == DIRECTED_SOFT_FACTOR  # kept, but dear
    assert costs["A1.1-A2.1"] == 1.0
    assert graph.route("A2.1", "A1.1").travel_time == pytest.approx(9.0)  # the detour: 9 < 15


def test_a_penalty_zone_sends_routes_around_it_when_a_detour_is_affordable(
    demo_map: Map,
) -> None:
    create_zone(
        map=demo_map,
        zone_id="busy",
        zone_type="PENALTY",
        vertices=box(4, 2.5, 11, 3.5),
        penalty_factor=0.9,
    )

    graph = load_graph(map=demo_map)
    route = graph.route("A1.1", "A4.1")

    assert not {"A2.1", "A3.1"} & set(route.nodes)
    assert route.length == pytest.approx(15.0)
    assert "A2.1" not in graph.shortest_path("A1.1", "A4.1")  # dispatch's distance view too


def test_a_restricted_zone_lets_in_only_the_vehicle_types_it_lists(demo_map: Map) -> None:
    forklift = VehicleType.objects.create(type_id="acme.forklift")
    create_zone(
        map=demo_map,
        zone_id="racks",
        zone_type="RESTRICTED",
        vertices=box(5, 10, 7, 12),
        vehicle_types=[forklift],
    )

    graph = load_graph(map=demo_map)

    assert graph.route("A0.0", "S-PICK-2", vehicle=VehicleProfile(vehicle_type="acme.forklift"))
    with pytest.raises(NoRouteError):
        graph.route("A0.0", "S-PICK-2", vehicle=VehicleProfile(vehicle_type="acme.tugger"))


def test_a_disabled_zone_does_nothing(demo_map: Map) -> None:
    create_zone(
        map=demo_map, zone_id="Z", zone_type="BLOCKED", vertices=box(5, 10, 7, 12), enabled=False
    )

    assert load_graph(map=demo_map).route("A0.0", "S-PICK-2")
    assert not [f for f in validate_layout(map=demo_map) if f.severity == "error"]


def test_the_graph_cache_is_dropped_whenever_zones_change(demo_map: Map) -> None:
    graph = load_graph(map=demo_map)
    assert load_graph(map=demo_map) is graph

    zone = create_zone(map=demo_map, zone_id="Z", zone_type="BLOCKED", vertices=box(5, 10, 7, 12))
    blocked = load_graph(map=demo_map)
    set_zones_enabled(zones=[zone], enabled=False)
    disabled = load_graph(map=demo_map)
    zone.refresh_from_db()
    update_zone(zone=zone, enabled=True, vertices=box(11, 10, 13, 12))
    moved = load_graph(map=demo_map)
    delete_zone(zone=zone)
    deleted = load_graph(map=demo_map)

    assert len({id(g) for g in (graph, blocked, disabled, moved, deleted)}) == 5
    with pytest.raises(NoRouteError):
        blocked.route("A0.0", "S-PICK-2")
    assert disabled.route("A0.0", "S-PICK-2")
    assert moved.route("A0.0", "S-PICK-2")
    with pytest.raises(NoRouteError):
        moved.route("A0.0", "S-PICK-4")
    assert deleted.route("A0.0", "S-PICK-4")


@pytest.mark.parametrize(
    ("fields", "field"),
    [
        ({"zone_type": "SPEED_LIMIT"}, "max_speed"),
        ({"zone_type": "DIRECTED", "limitation": "SOFT"}, "direction"),
        ({"zone_type": "BIDIRECTED", "direction": 0.0, "limitation": "STRICT"}, "limitation"),
        ({"zone_type": "PENALTY", "penalty_factor": 1.5}, "penalty_factor"),
        ({"zone_type": "PRIORITY"}, "priority_factor"),
        ({"zone_type": "RELEASE"}, "release_loss_behavior"),
        ({"zone_type": "BLOCKED", "vertices": box(0, 0, 1, 1)[:2]}, "vertices"),
        (
            {
                "zone_type": "BLOCKED",
                "vertices": [
                    {"x": 0, "y": 0},
                    {"x": 1, "y": 1},
                    {"x": 1, "y": 0},
                    {"x": 0, "y": 1},
                ],
            },
            "vertices",
        ),
    ],
)
def test_zone_data_must_fit_its_type(demo_map: Map, fields, field) -> None:
    data = {"vertices": box(0, 0, 1, 1), **fields}

    with pytest.raises(ZoneError) as caught:
        create_zone(map=demo_map, zone_id="Z", **data)

    assert field in caught.value.problems
    assert not Zone.objects.exists()


def test_vertices_are_stored_counter_clockwise(demo_map: Map) -> None:
    clockwise = [{"x": 0, "y": 0}, {"x": 0, "y": 1}, {"x": 1, "y": 1}, {"x": 1, "y": 0}]

    zone = create_zone(map=demo_map, zone_id="Z", zone_type="NO_STOPPING", vertices=clockwise)

    assert zone.vertices == clockwise[::-1]


def test_validation_reports_areas_and_overlapping_one_way_zones(demo_map: Map) -> None:
    create_zone(
        map=demo_map, zone_id="no-stop", zone_type="NO_STOPPING", vertices=box(5, 10, 7, 12)
    )
    create_zone(map=demo_map, zone_id="park", zone_type="PARKING", vertices=box(-3, -1, -1, 4))
    create_zone(map=demo_map, zone_id="charge", zone_type="CHARGING", vertices=box(16, 2, 18, 4))
    for zone_id, x in (("east", 0), ("west", 5)):
        create_zone(
            map=demo_map,
            zone_id=zone_id,
            zone_type="DIRECTED",
            vertices=box(x, 5.5, x + 8, 6.5),
            direction=0.0 if zone_id == "east" else 3.14159,
            limitation="SOFT",
        )

    found = {(f.code, f.object_id) for f in validate_layout(map=demo_map)}

    assert ("station-in-no-stopping-zone", "PICK-2") in found
    assert ("parking-outside-parking-area", "PARK-3") in found  # (-2, 6) is above the area
    assert ("parking-outside-parking-area", "PARK-1") not in found
    assert ("charger-outside-charging-area", "CHARGE-2") in found
    assert ("charger-outside-charging-area", "CHARGE-1") not in found
    assert ("directed-zones-overlap", "east") in found


def test_a_zone_broken_around_the_services_is_reported_and_ignored_by_routing(
    demo_map: Map,
) -> None:
    Zone.objects.create(
        map=demo_map, zone_id="bad", zone_type="SPEED_LIMIT", vertices=box(0, 0, 1, 1)
    )
    Zone.objects.create(map=demo_map, zone_id="worse", zone_type="BLOCKED", vertices=[{"x": 1}])
    mark_layout_changed(maps=[demo_map])

    findings = [f for f in validate_layout(map=demo_map) if f.code == "invalid-zone"]

    assert {f.object_id for f in findings} == {"bad", "worse"}
    assert load_graph(map=demo_map).route("A0.0", "A1.0")


def test_stations_keep_working_when_zones_are_elsewhere(demo_map: Map) -> None:
    create_zone(map=demo_map, zone_id="far", zone_type="BLOCKED", vertices=box(100, 100, 101, 101))

    graph = load_graph(map=demo_map)

    for station in Station.objects.filter(map=demo_map):
        assert graph.route("A0.0", station.node.node_id)


def test_enabled_zones_are_part_of_the_live_page_layout(demo_map: Map) -> None:
    create_zone(
        map=demo_map,
        zone_id="slow",
        zone_type="SPEED_LIMIT",
        max_speed=0.5,
        vertices=box(0, 0, 4, 4),
    )
    create_zone(
        map=demo_map, zone_id="off", zone_type="BLOCKED", vertices=box(5, 5, 6, 6), enabled=False
    )

    zones = layout_as_dict(map=demo_map)["zones"]

    assert [(z["id"], z["type"], z["maxSpeed"]) for z in zones] == [("slow", "SPEED_LIMIT", 0.5)]
    assert len(zones[0]["vertices"]) == 4
