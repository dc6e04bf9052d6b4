"""Zones through the API, the admin and LIF files (export under `openFleet`, import back)."""

import json

import pytest
from rest_framework.test import APIClient

from maps.models import Map, Station, VehicleType, Zone
from maps.selectors import export_map_lif, load_graph
from maps.services import create_zone, import_lif
from tests.factories import user_with_role
from tests.maps.zones_support import box
from traffic import NoRouteError

pytestmark = pytest.mark.django_db


def test_api_lists_zones_of_a_map(api, demo_map: Map) -> None:
    create_zone(map=demo_map, zone_id="Z1", zone_type="BLOCKED", vertices=box(5, 10, 7, 12))

    body = api.get("/api/v1/zones/", {"map": "demo"}).json()

    assert [z["zone_id"] for z in body["results"]] == ["Z1"]
    assert body["results"][0]["map"] == "demo"
    assert body["results"][0]["vertices"][0] == {"x": 5, "y": 10}


def test_api_creates_changes_and_deletes_a_zone_and_routing_follows(api, demo_map: Map) -> None:
    VehicleType.objects.create(type_id="acme.forklift")
    created = api.post(
        "/api/v1/zones/",
        {
            "map": "demo",
            "zone_id": "racks",
            "zone_type": "RESTRICTED",
            "vertices": box(5, 10, 7, 12),
            "vehicle_types": ["acme.forklift"],
        },
        format="json",
    )
    assert created.status_code == 201, created.content
    url = f"/api/v1/zones/{created.json()['id']}/"

    changed = api.patch(url, {"zone_type": "BLOCKED", "enabled": True}, format="json")
    blocked = load_graph(map=demo_map)
    deleted = api.delete(url)

    assert created.json()["vehicle_types"] == ["acme.forklift"]
    assert changed.status_code == 200, changed.content
    assert changed.json()["zone_type"] == "BLOCKED"
    with pytest.raises(NoRouteError):
        blocked.route("A0.0", "S-PICK-2")
    assert deleted.status_code == 204
    assert load_graph(map=demo_map).route("A0.0", "S-PICK-2")


def test_api_answers_400_per_field_for_zone_data_that_breaks_its_type(api, demo_map) -> None:
    response = api.post(
        "/api/v1/zones/",
        {"map": "demo", "zone_id": "slow", "zone_type": "SPEED_LIMIT", "vertices": box(0, 0, 1, 1)},
        format="json",
    )

    assert response.status_code == 400
    assert "max_speed" in response.json()
    assert not Zone.objects.exists()


def test_only_staff_change_zones_through_the_api(demo_map: Map) -> None:
    user = user_with_role("operator", "viewer", password="pw")  # reads layouts, changes none
    client = APIClient()
    client.force_authenticate(user)

    listed = client.get("/api/v1/zones/")
    refused = client.post(
        "/api/v1/zones/",
        {"map": "demo", "zone_id": "Z", "zone_type": "BLOCKED", "vertices": box(0, 0, 1, 1)},
        format="json",
    )

    assert listed.status_code == 200
    assert refused.status_code == 403


def test_api_gives_edge_speed_limits_after_zones(api, demo_map: Map) -> None:
    create_zone(
        map=demo_map,
        zone_id="slow",
        zone_type="SPEED_LIMIT",
        vertices=box(2, -0.5, 10, 0.5),
        max_speed=0.4,
    )

    body = api.get(f"/api/v1/maps/{demo_map.pk}/speed-limits/").json()

    assert body["edges"]["A1.0-A2.0"] == 0.4
    assert body["edges"]["A4.0-A5.0"] is None


def test_zones_are_exported_under_open_fleet_and_imported_back(demo_map: Map) -> None:
    forklift = VehicleType.objects.create(type_id="acme.forklift")
    create_zone(
        map=demo_map,
        zone_id="east",
        zone_type="DIRECTED",
        vertices=box(1, 2.5, 14, 3.5),
        direction=0.0,
        limitation="STRICT",
        name="one-way aisle",
    )
    create_zone(
        map=demo_map,
        zone_id="racks",
        zone_type="RESTRICTED",
        vertices=box(5, 10, 7, 12),
        vehicle_types=[forklift],
        enabled=False,
    )

    document = export_map_lif(map=demo_map)
    zones = document["layouts"][0]["openFleet"]["zones"]
    Station.objects.all().delete()
    Map.objects.all().delete()
    report = import_lif(source=document, site_id="plant")

    assert [z["zoneId"] for z in zones] == ["east", "racks"]
    assert zones[0] | {"vertices": None} == {
        "zoneId": "east",
        "zoneType": "DIRECTED",
        "mapId": "demo",
        "enabled": True,
        "vertices": None,
        "zoneDescriptor": "one-way aisle",
        "direction": 0.0,
        "directedLimitation": "STRICT",
    }
    assert zones[1]["vehicleTypeIds"] == ["acme.forklift"]
    assert report.ok, report.as_dict()
    assert report.counts["zones"] == 2
    east, racks = Zone.objects.order_by("zone_id")
    assert (east.zone_type, east.limitation, east.name) == ("DIRECTED", "STRICT", "one-way aisle")
    assert east.vertices == box(1, 2.5, 14, 3.5)
    assert (racks.enabled, [t.type_id for t in racks.vehicle_types.all()]) == (
        False,
        ["acme.forklift"],
    )


def test_a_zone_in_a_lif_file_that_breaks_its_type_is_an_error_with_its_path(
    demo_map: Map,
) -> None:
    create_zone(
        map=demo_map,
        zone_id="slow",
        zone_type="SPEED_LIMIT",
        vertices=box(0, 0, 1, 1),
        max_speed=1.0,
    )
    document = export_map_lif(map=demo_map)
    del document["layouts"][0]["openFleet"]["zones"][0]["maximumSpeed"]
    document["metaInformation"]["projectIdentification"] = "other"

    report = import_lif(source=document, site_id="plant")

    assert not report.ok
    assert any(e.path == "$.layouts[0].openFleet.zones[0].maximumSpeed" for e in report.errors), (
        report.as_dict()
    )


def test_admin_saves_a_zone_and_routing_sees_it(client, staff, demo_map: Map) -> None:
    client.force_login(staff)
    graph = load_graph(map=demo_map)

    response = client.post(
        "/admin/maps/zone/add/",
        {
            "map": demo_map.pk,
            "zone_id": "Z",
            "zone_type": "BLOCKED",
            "enabled": "on",
            "vertices": json.dumps(box(5, 10, 7, 12)[::-1]),  # clockwise
            "entry_actions": "[]",
            "during_actions": "[]",
            "exit_actions": "[]",
        },
    )

    assert response.status_code == 302, response.content.decode()[:2000]
    assert Zone.objects.get().vertices[0] == {"x": 5, "y": 10}  # turned counter-clockwise
    assert load_graph(map=demo_map) is not graph
    with pytest.raises(NoRouteError):
        load_graph(map=demo_map).route("A0.0", "S-PICK-2")


def test_admin_refuses_a_zone_that_breaks_its_type(client, staff, demo_map: Map) -> None:
    client.force_login(staff)

    response = client.post(
        "/admin/maps/zone/add/",
        {
            "map": demo_map.pk,
            "zone_id": "Z",
            "zone_type": "SPEED_LIMIT",
            "vertices": '[{"x": 0, "y": 0}, {"x": 1, "y": 0}, {"x": 1, "y": 1}]',
            "entry_actions": "[]",
            "during_actions": "[]",
            "exit_actions": "[]",
        },
    )

    assert response.status_code == 200
    assert "a speed limit zone needs a speed" in response.content.decode()
    assert not Zone.objects.exists()


def test_admin_actions_enable_and_disable_zones(client, staff, demo_map: Map) -> None:
    client.force_login(staff)
    zone = create_zone(map=demo_map, zone_id="Z", zone_type="BLOCKED", vertices=box(5, 10, 7, 12))

    client.post(
        "/admin/maps/zone/", {"action": "disable", "_selected_action": [zone.pk]}, follow=True
    )

    zone.refresh_from_db()
    assert zone.enabled is False
    assert load_graph(map=demo_map).route("A0.0", "S-PICK-2")


def test_admin_map_page_links_to_the_layout_editor(client, staff, demo_map: Map) -> None:
    client.force_login(staff)

    page = client.get(f"/admin/maps/map/{demo_map.pk}/change/").content.decode()
    listing = client.get("/admin/maps/map/").content.decode()

    assert f'href="/layouts/{demo_map.pk}/edit/"' in page
    assert f'href="/layouts/{demo_map.pk}/edit/"' in listing


def test_a_nul_character_in_a_query_parameter_is_a_400_not_a_500(api) -> None:
    """PostgreSQL refuses NUL in text (psycopg raises DataError before sending): a bad request,
    answered with the reason, like any other bad input."""
    response = api.get("/api/v1/zones/", {"map": "de\x00mo"})
    assert response.status_code == 400
    assert "database cannot take" in response.json()["detail"]
