"""The ways in: API endpoints, management commands and the admin for LIF and validation."""

import json

import pytest
from django.core.files.uploadedfile import SimpleUploadedFile
from django.core.management import CommandError, call_command
from rest_framework.test import APIClient

from maps.models import Map, Node, Site
from maps.services import import_lif
from tests.factories import user_with_role
from tests.maps.support import example, lif, row_counts

pytestmark = pytest.mark.django_db


def upload(name: str, document: dict) -> SimpleUploadedFile:
    return SimpleUploadedFile(name, json.dumps(document).encode(), "application/json")


def test_api_upload_imports_and_returns_the_report(api) -> None:
    response = api.post(
        "/api/v1/lif/import/",
        {"file": upload("ex14.json", example("10.14_")), "site": "plant"},
        format="multipart",
    )

    assert response.status_code == 201, response.content
    body = response.json()
    assert body["ok"] is True
    assert body["maps"] == ["Map_Z-Level_1", "Map_Z-Level_2"]
    assert body["counts"]["edges"] == 5
    assert Site.objects.get().site_id == "plant"


def test_api_upload_of_a_json_body_with_errors_is_422_with_paths_and_writes_nothing(
    api, demo_map
) -> None:
    before = row_counts()
    document = lif([("a", 0, 0)], [("a", "b")])

    response = api.post("/api/v1/lif/import/?site=plant", document, format="json")

    assert response.status_code == 422
    assert response.json()["errors"] == ['$.layouts[0].edges[0].endNodeId: unknown node "b"']
    assert row_counts() == before


def test_api_upload_needs_staff(db) -> None:
    client = APIClient()
    client.force_authenticate(user_with_role("operator", "erp"))

    response = client.post("/api/v1/lif/import/", example("10.1_"), format="json")

    assert response.status_code == 403
    assert not Map.objects.exists()


def test_api_exports_a_map_and_a_site_as_lif(api) -> None:
    import_lif(source=example("10.14_"), site_id="plant")
    ground = Map.objects.get(map_id="Map_Z-Level_1")

    one = api.get(f"/api/v1/maps/{ground.pk}/lif/")
    site = api.get(f"/api/v1/sites/{Site.objects.get().pk}/lif/")

    assert one.status_code == 200
    assert "attachment" in one["Content-Disposition"]
    assert [la["layoutId"] for la in one.json()["layouts"]] == ["Layout_Ground_Level"]
    assert [len(la["edges"]) for la in site.json()["layouts"]] == [2, 3]
    assert site.json()["metaInformation"]["lifVersion"] == "1.0.0"


def test_api_validation_lists_findings(api, demo_map) -> None:
    response = api.get(f"/api/v1/maps/{demo_map.pk}/validation/")

    assert response.json() == {"map": "demo", "errors": 0, "warnings": 0, "findings": []}


def test_commands_import_export_and_validate(tmp_path, capsys) -> None:
    source = tmp_path / "plant.json"
    source.write_text(json.dumps(example("10.7_")))
    out = tmp_path / "out.json"

    call_command("import_lif", str(source), "--site", "plant")
    call_command("export_lif", "Map_Z-Level_1", "--output", str(out))
    call_command("validate_layout", "Map_Z-Level_1")

    printed = capsys.readouterr().out
    assert "imported: LIF Example 07 into site plant" in printed
    assert "Map_Z-Level_1: 0 error(s)" in printed
    assert len(json.loads(out.read_text())["layouts"][0]["nodes"]) == 5


def test_the_import_command_fails_on_errors_and_validate_on_layout_errors(tmp_path) -> None:
    bad = tmp_path / "bad.json"
    bad.write_text('{"layouts": 3}')
    with pytest.raises(CommandError, match="nothing imported"):
        call_command("import_lif", str(bad))

    import_lif(source=example("10.1_"), site_id="plant")  # a forward edge only: N2 is a dead end
    with pytest.raises(CommandError, match="error"):
        call_command("validate_layout", "Map_Z-Level_1")


def test_admin_upload_shows_the_report(client, staff) -> None:
    client.force_login(staff)

    page = client.get("/admin/maps/lifimport/add/", follow=True)
    posted = client.post(
        "/admin/maps/lifimport/upload/",
        {"file": upload("ex6.json", example("10.6_")), "site": "plant"},
    )
    broken = client.post(
        "/admin/maps/lifimport/upload/",
        {
            "file": upload("bad.json", lif([("a", 0, 0)], [("a", "zz")], project="p2")),
            "site": "plant",
        },
    )

    assert page.status_code == 200
    assert b"Import a LIF file" in page.content
    assert b"Imported" in posted.content
    assert Node.objects.filter(map__site__site_id="plant").count() == 2
    assert b"nothing was written" in broken.content
    assert b"unknown node" in broken.content


def test_admin_actions_validate_and_export(client, staff, demo_map) -> None:
    client.force_login(staff)
    data = {"_selected_action": [demo_map.pk]}

    validated = client.post("/admin/maps/map/", {**data, "action": "validate"}, follow=True)
    exported = client.post("/admin/maps/map/", {**data, "action": "export"})

    assert b"demo: 0 error(s), 0 warning(s)" in validated.content.lower()
    assert json.loads(exported.content)["layouts"][0]["layoutId"] == "demo"


def test_admin_edits_of_the_graph_mark_the_map_changed(client, staff, demo_map) -> None:
    client.force_login(staff)
    node = Node.objects.get(map=demo_map, node_id="A0.0")

    client.post(
        f"/admin/maps/node/{node.pk}/change/",
        {
            "map": demo_map.pk,
            "node_id": "A0.0",
            "x": "0.5",
            "y": "0",
            "theta": "",
            "name": "",
            "description": "",
            "layout": "",
            "source_id": "",
            "properties-TOTAL_FORMS": "0",
            "properties-INITIAL_FORMS": "0",
        },
    )

    demo_map.refresh_from_db()
    assert Node.objects.get(pk=node.pk).x == 0.5
    assert demo_map.revision == 1
