"""Released map files (issue 4 item 7, REFERENCE K.47): release, download, distribute, API,
admin, and what `control` reads and writes of them."""

import hashlib
import json

import pytest
from django.urls import reverse
from rest_framework.test import APIClient

from control import map_store
from control.map_status import outdated_vehicle_maps
from control.map_sync import MapStatus
from control.models import VehicleMap
from fleet.exceptions import InvalidRequestError
from maps.demo import warehouse_layout
from maps.models import Map, MapRelease
from maps.selectors import current_releases, release_by_token
from maps.services import create_layout, create_zone, distribute_release, release_map
from robots.models import Vehicle
from tests.factories import user_with_role
from tests.maps.zones_support import box

pytestmark = pytest.mark.django_db


@pytest.fixture
def layout() -> Map:
    return create_layout(spec=warehouse_layout(columns=3, rows=2))


@pytest.fixture
def commands(monkeypatch: pytest.MonkeyPatch) -> list[dict]:
    """What the services queue for `control` (the Redis list is the boundary)."""
    queued: list[dict] = []
    monkeypatch.setattr(
        "maps.services.releases.send_command",
        lambda kind, **payload: queued.append({"kind": kind, **payload}),
    )
    return queued


def test_a_release_freezes_the_layout_as_a_lif_file_with_its_checksum(layout, staff) -> None:
    release = release_map(map=layout, user=staff, note="first")

    content = bytes(release.content)
    assert (release.number, release.version) == (1, "r1")
    assert release.checksum == hashlib.sha256(content).hexdigest()
    assert release.size == len(content)
    assert release.revision == layout.revision
    document = json.loads(content)
    (lif_layout,) = document["layouts"]
    assert len(lif_layout["nodes"]) == layout.nodes.count()
    assert release.created_by == staff
    assert release.distributed_at is None
    assert release_map(map=layout).version == "r2"


def test_the_same_layout_gives_the_same_file(layout) -> None:
    first, second = release_map(map=layout), release_map(map=layout)
    assert first.checksum == second.checksum
    assert first.token != second.token


def test_a_map_without_nodes_cannot_be_released(layout) -> None:
    empty = Map.objects.create(map_id="empty", name="empty")
    with pytest.raises(InvalidRequestError, match="no nodes"):
        release_map(map=empty)
    assert not MapRelease.objects.exists()


def test_distributing_makes_a_release_current_and_wakes_control(
    layout, commands, django_capture_on_commit_callbacks
) -> None:
    with django_capture_on_commit_callbacks(execute=True):
        first = release_map(map=layout, distribute=True)
        second = release_map(map=layout)
    assert current_releases() == {"demo": first}
    assert commands == [{"kind": "maps.distribute", "map_id": "demo", "version": "r1"}]

    with django_capture_on_commit_callbacks(execute=True):
        distribute_release(release=second)
    assert current_releases()["demo"].version == "r2"
    with django_capture_on_commit_callbacks(execute=True):
        distribute_release(release=first)  # a rollback is a distribution too
    assert current_releases()["demo"].version == "r1"


def test_vehicles_download_the_file_by_its_token_without_logging_in(client, layout) -> None:
    release = release_map(map=layout)
    url = reverse("maps:release-file", args=[release.token, release.file_name])

    response = client.get(url)

    assert response.status_code == 200
    assert response.content == bytes(release.content)
    assert response["X-Checksum-SHA256"] == release.checksum
    assert client.get(url.replace(release.token, "guessed")).status_code == 404
    assert client.get(url.replace(".lif.json", ".json")).status_code == 404
    assert client.post(url).status_code == 405
    assert release_by_token(token=release.token) == release


def test_the_api_releases_and_distributes_for_staff_only(api, layout, commands) -> None:
    response = api.post("/api/v1/map-releases/", {"map": "demo", "note": "n"}, format="json")
    assert response.status_code == 201, response.content
    body = response.json()
    assert (body["map"], body["version"], body["distributed_at"]) == ("demo", "r1", None)
    assert body["download"].endswith("/demo-r1.lif.json")

    response = api.post(f"/api/v1/map-releases/{body['id']}/distribute/")
    assert response.status_code == 200
    assert response.json()["distributed_at"] is not None
    assert [r["version"] for r in api.get("/api/v1/map-releases/?map=demo").json()["results"]] == [
        "r1"
    ]
    assert api.post("/api/v1/map-releases/", {"map": "nope"}, format="json").status_code == 404
    Map.objects.create(map_id="empty", name="empty")
    refused = api.post("/api/v1/map-releases/", {"map": "empty"}, format="json")
    assert refused.status_code == 422
    assert "no nodes" in refused.json()["detail"]

    reader = APIClient()
    reader.force_authenticate(user_with_role("operator", "reader", password="pw"))
    assert reader.get("/api/v1/map-releases/").status_code == 200
    assert reader.post("/api/v1/map-releases/", {"map": "demo"}, format="json").status_code == 403
    assert MapRelease.objects.count() == 1


def test_the_admin_releases_maps_and_distributes_releases(client, staff, layout, commands) -> None:
    client.force_login(staff)
    response = client.post(
        reverse("admin:maps_map_changelist"),
        {"action": "release_and_distribute", "_selected_action": [layout.pk]},
        follow=True,
    )
    assert response.status_code == 200
    release = MapRelease.objects.get()
    assert release.distributed_at is not None
    page = client.get(reverse("admin:maps_maprelease_change", args=[release.pk]))
    assert release.file_name in page.content.decode()

    second = release_map(map=layout)
    changelist = reverse("admin:maps_maprelease_changelist")
    both = {"action": "distribute", "_selected_action": [release.pk, second.pk]}
    client.post(changelist, both, follow=True)
    assert MapRelease.objects.get(pk=second.pk).distributed_at is None  # one per map
    client.post(changelist, {"action": "distribute", "_selected_action": [second.pk]})
    assert current_releases()["demo"] == second


@pytest.mark.django_db(transaction=True)  # the store closes stale connections
def test_control_reads_the_targets_with_links_and_the_zone_sets(
    layout, monkeypatch: pytest.MonkeyPatch, commands
) -> None:
    monkeypatch.setenv("FLEET_PUBLIC_URL", "http://fleet.example:8000/")
    release = release_map(map=layout, distribute=True)
    create_zone(
        map=layout, zone_id="Z1", zone_type="SPEED_LIMIT", vertices=box(0, 0, 4, 4), max_speed=0.5
    )
    create_zone(map=layout, zone_id="Z2", zone_type="PARKING", vertices=box(5, 5, 6, 6))

    targets, zone_sets = map_store.load_targets()

    target = targets["demo"]
    assert target.version == "r1"
    assert target.checksum == release.checksum
    assert (
        target.link
        == f"http://fleet.example:8000/layouts/releases/{release.token}/demo-r1.lif.json"
    )
    assert [(z.zone_id, str(z.zone_type)) for z in zone_sets["demo"].zones] == [
        ("Z1", "SPEED_LIMIT")
    ]


@pytest.mark.django_db(transaction=True)
def test_control_saves_each_vehicles_map_status_and_outdated_ones_show(layout) -> None:
    vehicle = Vehicle.objects.create(manufacturer="sim", serial_number="AGV-1")
    old = MapStatus("demo", "r2", "1", "DOWNLOADING", "held", (("1", "ENABLED"),))
    map_store.save_map_statuses([(vehicle.pk, old, "", "")])
    synced = MapStatus("demo", "r2", "r2", "SYNCED", "", (("r2", "ENABLED"),))
    map_store.save_map_statuses([(vehicle.pk, synced, "demo.abc", "ENABLED")])
    map_store.save_map_statuses([])

    (row,) = VehicleMap.objects.all()
    assert (row.status, row.enabled_version, row.zone_set_status) == ("SYNCED", "r2", "ENABLED")
    assert row.reported == [{"mapVersion": "r2", "mapStatus": "ENABLED"}]
    assert not row.outdated
    row.enabled_version = "1"
    assert row.outdated


def test_vehicles_on_another_version_than_the_released_one_are_listed(client, staff) -> None:
    on_time = Vehicle.objects.create(manufacturer="sim", serial_number="AGV-1")
    behind = Vehicle.objects.create(manufacturer="sim", serial_number="AGV-2")
    VehicleMap.objects.create(
        vehicle=on_time, map_id="demo", released_version="r2", enabled_version="r2", status="SYNCED"
    )
    VehicleMap.objects.create(
        vehicle=behind,
        map_id="demo",
        released_version="r2",
        enabled_version="1",
        status="DOWNLOADING",
        reason="vehicle has map demo version 1 enabled, the released version is r2",
    )
    VehicleMap.objects.create(
        vehicle=behind, map_id="hall", enabled_version="7", status="NO_RELEASE"
    )

    assert [r.vehicle.serial_number for r in outdated_vehicle_maps()] == ["AGV-2"]
    assert list(outdated_vehicle_maps(map_id="hall")) == []
    client.force_login(staff)
    page = client.get(reverse("admin:control_vehiclemap_changelist") + "?outdated=yes")
    assert page.status_code == 200
    text = page.content.decode()
    assert "the released version is r2" in text
    assert "AGV-1" not in text
