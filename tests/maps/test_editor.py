"""The layout editor's server side: saving whole layouts as versions, checking drafts, the pages."""

import json
import time
from typing import Any

import pytest
from django.core.files.base import ContentFile
from django.test import Client

from maps.demo import warehouse_layout
from maps.models import Edge, Map, MapVersion, Node, NodeProperty, Station, VehicleType, Zone
from maps.selectors import editor_data, load_graph, validate_layout
from maps.services import (
    LayoutConflictError,
    LayoutPayloadError,
    check_layout_draft,
    create_layout,
    import_lif,
    save_layout_version,
)
from orders.models import TransportOrder
from tests.factories import user_with_role
from tests.maps.support import lif
from tests.maps.zones_support import box

pytestmark = pytest.mark.django_db


def small_payload(**extra: Any) -> dict[str, Any]:
    """Four nodes in a square, two-way edges around it, a pick and a drop station on spurs."""
    nodes = [("N1", 0, 0), ("N2", 4, 0), ("N3", 4, 4), ("N4", 0, 4), ("P", 2, -2), ("D", 2, 6)]
    pairs = [("N1", "N2"), ("N2", "N3"), ("N3", "N4"), ("N4", "N1")]
    edges = [
        {"id": f"{a}-{b}", "start": a, "end": b} for x, y in pairs for a, b in ((x, y), (y, x))
    ]
    edges += [
        {"id": "N1-P", "start": "N1", "end": "P"},
        {"id": "P-N1", "start": "P", "end": "N1"},
        {"id": "N4-D", "start": "N4", "end": "D"},
        {"id": "D-N4", "start": "D", "end": "N4"},
    ]
    return {
        "nodes": [{"id": i, "x": x, "y": y} for i, x, y in nodes],
        "edges": edges,
        "stations": [
            {"id": "PICK-1", "name": "Goods in", "kind": "PICK", "nodes": ["P"]},
            {"id": "DROP-1", "kind": "DROP", "nodes": ["D"]},
        ],
        "zones": [],
        **extra,
    }


@pytest.fixture
def empty_map(db: None) -> Map:
    return create_layout(spec={"mapId": "hall", "name": "Hall", "nodes": [], "edges": []})


def test_saving_writes_the_layout_as_version_one_and_it_validates(empty_map: Map, staff) -> None:
    revision = empty_map.revision

    version = save_layout_version(map=empty_map, payload=small_payload(note="first"), user=staff)

    empty_map.refresh_from_db()
    assert (version.number, empty_map.version) == (1, 1)
    assert empty_map.revision == revision + 1 == version.revision
    assert (version.saved_by, version.note) == (staff, "first")
    assert version.counts == {"nodes": 6, "edges": 12, "stations": 2, "zones": 0}
    assert Node.objects.filter(map=empty_map).count() == 6
    assert Edge.objects.get(edge_id="N1-N2").length == pytest.approx(4.0)
    pick = Station.objects.get(station_id="PICK-1")
    assert (pick.name, pick.kind, pick.node.node_id) == ("Goods in", "PICK", "P")
    assert [sn.node.node_id for sn in pick.station_nodes.all()] == ["P"]
    assert validate_layout(map=empty_map) == []
    assert load_graph(map=empty_map).route("P", "D").nodes == ["P", "N1", "N4", "D"]


def test_a_second_save_changes_only_what_differs_and_keeps_what_the_editor_does_not_show(
    db: None,
) -> None:
    import_lif(
        source=lif(
            [("a", 0, 0), ("b", 3, 0), ("c", 6, 0)],
            [("a", "b"), ("b", "a"), ("b", "c"), ("c", "b")],
        )
    )
    layout = Map.objects.get()
    data = editor_data(map=layout)
    data_nodes = {n["id"]: n for n in data["nodes"]}
    data_nodes["c"]["x"] = 9.0  # moved
    payload = {
        "baseRevision": data["map"]["revision"],
        "nodes": list(data_nodes.values()),
        "edges": [e for e in data["edges"] if e["id"] != "c-b"],  # one deleted
        "stations": [],
        "zones": [],
    }

    save_layout_version(map=layout, payload=payload)

    assert Edge.objects.get(edge_id="b-c").length == pytest.approx(6.0)  # follows the node
    assert not Edge.objects.filter(edge_id="c-b").exists()
    assert NodeProperty.objects.filter(node__node_id="a").exists()  # LIF properties survive
    assert Edge.objects.get(edge_id="a-b").properties.count() == 1
    assert Node.objects.get(node_id="a").layout is not None


def test_zones_are_saved_with_the_layout_and_routing_uses_them(empty_map: Map) -> None:
    VehicleType.objects.create(type_id="acme.forklift")
    zones = [
        {"id": "Z1", "type": "BLOCKED", "vertices": box(1, 5, 3, 7), "name": "spill"},
        {
            "id": "Z2",
            "type": "RESTRICTED",
            "vertices": box(-1, -3, 1, -1),
            "vehicleTypes": ["acme.forklift"],
            "enabled": False,
        },
    ]

    save_layout_version(map=empty_map, payload=small_payload(zones=zones))

    blocked = Zone.objects.get(zone_id="Z1")
    assert (blocked.zone_type, blocked.name, blocked.enabled) == ("BLOCKED", "spill", True)
    restricted = Zone.objects.get(zone_id="Z2")
    assert [t.type_id for t in restricted.vehicle_types.all()] == ["acme.forklift"]
    codes = {(f.code, f.object_id) for f in validate_layout(map=empty_map)}
    assert ("station-in-blocked-zone", "DROP-1") in codes


def test_every_problem_is_reported_with_its_path_and_nothing_is_written(empty_map: Map) -> None:
    payload = small_payload()
    payload["nodes"][1]["x"] = "far"
    payload["nodes"].append({"id": "N1", "x": 1, "y": 1})
    payload["edges"].append({"id": "bad", "start": "N1", "end": "nowhere"})
    payload["stations"][1]["kind"] = "SHELF"
    payload["zones"] = [{"id": "Z", "type": "SPEED_LIMIT", "vertices": box(0, 0, 1, 1)}]
    payload["colour"] = "blue"

    with pytest.raises(LayoutPayloadError) as caught:
        save_layout_version(map=empty_map, payload=payload)

    found = {(p.path, p.message) for p in caught.value.problems}
    paths = {path for path, _ in found}
    assert {
        "$.nodes[1].x",
        "$.nodes[6].id",
        "$.edges[12].end",
        "$.stations[1].kind",
        "$.zones[0].maxSpeed",
        "$.colour",
    } <= paths, found
    assert not Node.objects.filter(map=empty_map).exists()
    assert not MapVersion.objects.exists()


def test_a_save_based_on_an_older_revision_is_refused(empty_map: Map) -> None:
    save_layout_version(map=empty_map, payload=small_payload(baseRevision=empty_map.revision))

    with pytest.raises(LayoutConflictError, match="reload"):
        save_layout_version(map=empty_map, payload=small_payload(baseRevision=0))

    assert MapVersion.objects.count() == 1


def test_a_station_that_transport_orders_use_cannot_be_deleted(empty_map: Map) -> None:
    save_layout_version(map=empty_map, payload=small_payload())
    TransportOrder.objects.create(
        source=Station.objects.get(station_id="PICK-1"),
        destination=Station.objects.get(station_id="DROP-1"),
    )
    payload = small_payload()
    payload["stations"] = payload["stations"][1:]

    with pytest.raises(LayoutPayloadError) as caught:
        save_layout_version(map=empty_map, payload=payload)

    assert "station PICK-1 cannot be deleted" in caught.value.problems[0].message
    assert Station.objects.filter(station_id="PICK-1").exists()


def test_ids_stay_unique_across_the_maps_of_a_site(db: None) -> None:
    create_layout(spec={**warehouse_layout(columns=2, rows=2, map_id="floor-1"), "site": "plant"})
    floor_2 = create_layout(
        spec={"mapId": "floor-2", "name": "2", "site": "plant", "nodes": [], "edges": []}
    )
    payload = small_payload()
    payload["nodes"][0]["id"] = "A0.0"
    for edge in payload["edges"]:
        edge["start"] = "A0.0" if edge["start"] == "N1" else edge["start"]
        edge["end"] = "A0.0" if edge["end"] == "N1" else edge["end"]

    with pytest.raises(LayoutPayloadError) as caught:
        save_layout_version(map=floor_2, payload=payload)

    assert caught.value.problems[0].path == "$.nodes[0].id"
    assert "floor-1" in caught.value.problems[0].message
    assert editor_data(map=floor_2)["takenIds"]["nodes"]


def test_checking_a_draft_reports_its_findings_and_writes_nothing(empty_map: Map) -> None:
    payload = small_payload()
    payload["edges"] = [e for e in payload["edges"] if e["id"] != "D-N4"]  # a dead end

    problems, findings = check_layout_draft(map=empty_map, payload=payload)

    assert problems == []
    assert ("error", "dead-end", "D") in {(f.severity, f.code, f.object_id) for f in findings}
    empty_map.refresh_from_db()
    assert not Node.objects.filter(map=empty_map).exists()
    assert (empty_map.revision, empty_map.version) == (0, 0)


def test_saving_a_5000_node_layout_with_one_node_moved_is_quick(db: None) -> None:
    layout = create_layout(spec=warehouse_layout(columns=100, rows=50, map_id="big"))
    data = editor_data(map=layout)
    data["nodes"][10]["x"] += 0.5
    payload = {k: data[k] for k in ("nodes", "edges", "stations", "zones")}
    payload["baseRevision"] = data["map"]["revision"]

    started = time.perf_counter()
    save_layout_version(map=layout, payload=json.loads(json.dumps(payload)))
    seconds = time.perf_counter() - started

    assert len(data["nodes"]) > 5000
    assert seconds < 10, f"{seconds:.1f} s"
    assert Node.objects.get(map=layout, node_id=data["nodes"][10]["id"]).x == data["nodes"][10]["x"]


# ---------------------------------------------------------------- pages and endpoints


def post_json(client: Client, url: str, payload: Any) -> Any:
    return client.post(url, json.dumps(payload), content_type="application/json")


def test_pages_need_a_staff_login(empty_map: Map) -> None:
    client = Client()
    anonymous = client.get(f"/layouts/{empty_map.pk}/edit/")
    user = user_with_role("operator", "driver", password="pw")  # no MANAGE_LAYOUTS
    client.force_login(user)
    not_staff = client.get(f"/layouts/{empty_map.pk}/edit/")
    save = post_json(client, f"/layouts/{empty_map.pk}/save/", small_payload())

    assert anonymous.status_code == 302
    assert "/accounts/login/" in anonymous["Location"]
    assert not_staff.status_code == 403
    assert save.status_code == 403
    assert not Node.objects.exists()


def test_the_editor_page_carries_the_layout_and_the_nav_links_to_layouts(
    client: Client, staff, demo_map: Map
) -> None:
    client.force_login(staff)

    page = client.get(f"/layouts/{demo_map.pk}/edit/")

    html = page.content.decode()
    assert page.status_code == 200
    assert 'id="editor-data"' in html
    assert "maps/editor.js" in html
    assert 'href="/layouts/"' in html
    assert page.context["data"]["map"]["mapId"] == "demo"
    assert len(page.context["data"]["nodes"]) == demo_map.nodes.count()


def test_save_endpoint_needs_the_csrf_token(staff, empty_map: Map) -> None:
    client = Client(enforce_csrf_checks=True)
    client.force_login(staff)
    client.get(f"/layouts/{empty_map.pk}/edit/")
    url = f"/layouts/{empty_map.pk}/save/"

    refused = post_json(client, url, small_payload())
    accepted = client.post(
        url,
        json.dumps(small_payload()),
        content_type="application/json",
        headers={"X-CSRFToken": client.cookies["csrftoken"].value},
    )

    assert refused.status_code == 403
    assert accepted.status_code == 200, accepted.content
    assert accepted.json()["version"] == 1
    assert accepted.json()["findings"] == []


def test_save_endpoint_answers_422_with_problems_and_409_on_conflict(
    client: Client, staff, empty_map: Map
) -> None:
    client.force_login(staff)
    url = f"/layouts/{empty_map.pk}/save/"
    broken = small_payload()
    broken["edges"][0]["end"] = "N9"

    invalid = post_json(client, url, broken)
    stale = post_json(client, url, small_payload(baseRevision=99))
    not_json = client.post(url, "nodes", content_type="application/json")

    assert invalid.status_code == 422
    assert invalid.json()["problems"] == [
        {"path": "$.edges[0].end", "message": "unknown node 'N9'"}
    ]
    assert stale.status_code == 409
    assert not_json.status_code == 400


def test_check_endpoint_lists_findings(client: Client, staff, empty_map: Map) -> None:
    client.force_login(staff)
    payload = small_payload()
    payload["edges"] = [e for e in payload["edges"] if e["id"] != "D-N4"]

    body = post_json(client, f"/layouts/{empty_map.pk}/check/", payload).json()

    assert body["problems"] == []
    assert {"severity": "error", "code": "dead-end", "object_type": "node", "object_id": "D"} | {
        "message": body["findings"][0]["message"]
    } in body["findings"]


def test_list_page_creates_a_map_and_opens_it_in_the_editor(client: Client, staff) -> None:
    client.force_login(staff)

    listing = client.get("/layouts/")
    created = client.post("/layouts/", {"map_id": "hall-2", "name": "Hall 2", "site": "plant"})
    duplicate = client.post("/layouts/", {"map_id": "hall-2", "name": "again"})

    layout = Map.objects.get(map_id="hall-2")
    assert listing.status_code == 200
    assert created.status_code == 302
    assert created["Location"] == f"/layouts/{layout.pk}/edit/"
    assert layout.site.site_id == "plant"
    assert "exists already" in duplicate.content.decode()


def test_the_floor_plan_is_served_behind_the_login(
    client: Client, staff, demo_map, settings, tmp_path
) -> None:
    settings.MEDIA_ROOT = str(tmp_path)
    demo_map.floor_plan.save("hall.png", ContentFile(b"\x89PNG\r\n\x1a\n"), save=True)
    url = f"/layouts/{demo_map.pk}/floor-plan/"

    anonymous = client.get(url)
    client.force_login(staff)
    served = client.get(url)

    assert anonymous.status_code == 302
    assert served.status_code == 200
    assert served["Content-Type"] == "image/png"
    assert b"".join(served.streaming_content).startswith(b"\x89PNG")
    assert editor_data(map=demo_map)["map"]["floorPlan"]["url"] == url
