"""The audit trail: who did what from where, append-only, searchable and exportable."""

import pytest
from django.contrib.auth import get_user_model
from django.contrib.auth.models import AnonymousUser, Permission
from django.http import HttpRequest, HttpResponse
from django.test import Client, RequestFactory

from fleet.audit import AuditMiddleware, acting_as, record
from fleet.models import AuditEntry

pytestmark = pytest.mark.django_db


def test_a_request_records_its_user_and_address() -> None:
    user = get_user_model().objects.create_user("olga")

    def view(request: HttpRequest) -> HttpResponse:
        record("order.cancel", target_type="order", target_id=42, detail={"reason": "wrong"})
        return HttpResponse()

    request = RequestFactory().post("/x", REMOTE_ADDR="10.1.2.3")
    request.user = user
    AuditMiddleware(view)(request)
    anonymous = RequestFactory().get("/y", REMOTE_ADDR="10.9.9.9")
    anonymous.user = AnonymousUser()
    AuditMiddleware(lambda r: record("vehicle.pause", target_id="AGV-1") and HttpResponse())(
        anonymous
    )

    first, second = AuditEntry.objects.order_by("pk")
    assert (first.actor, first.user, first.source, first.action) == (
        "olga",
        user,
        "10.1.2.3",
        "order.cancel",
    )
    assert (first.target_type, first.target_id, first.detail) == (
        "order",
        "42",
        {"reason": "wrong"},
    )
    assert (second.actor, second.source) == ("anonymous", "10.9.9.9")


def test_processes_name_themselves_and_the_name_ends_with_the_block() -> None:
    with acting_as("system:dispatch"):
        record("order.assign", target_type="order", target_id=7)
    record("order.assign", target_id=8)
    assert list(AuditEntry.objects.order_by("pk").values_list("actor", flat=True)) == [
        "system:dispatch",
        "system:unknown",
    ]


def test_entries_can_be_neither_changed_nor_deleted() -> None:
    entry = record("layout.save", target_type="map", target_id="demo")
    entry.action = "nothing happened"
    with pytest.raises(ValueError, match="never changed"):
        entry.save()
    with pytest.raises(ValueError, match="never deleted"):
        entry.delete()
    admin = Client()
    admin.force_login(get_user_model().objects.create_superuser("root"))
    page = admin.get(f"/admin/fleet/auditentry/{entry.pk}/change/")
    assert page.status_code == 200
    assert "Save" not in page.content.decode()  # view only
    assert admin.post(f"/admin/fleet/auditentry/{entry.pk}/delete/").status_code == 403


def test_the_page_searches_and_the_csv_exports_for_those_allowed() -> None:
    with acting_as("system:control"):
        record(
            "vehicle.command", target_type="vehicle", target_id="AGV-1", detail={"action": "pause"}
        )
        record("order.cancel", target_type="order", target_id="9")
    auditor = get_user_model().objects.create_user("auditor")
    client = Client()
    client.force_login(auditor)
    assert client.get("/audit/").status_code == 403  # signed in, without the permission
    auditor.user_permissions.add(Permission.objects.get(codename="view_auditentry"))
    page = client.get("/audit/?q=AGV-1")
    assert page.status_code == 200
    assert "vehicle.command" in page.content.decode()
    assert "order.cancel" not in page.content.decode()
    exported = b"".join(client.get("/audit.csv?action=order").streaming_content).decode()
    assert exported.splitlines()[0] == "at,actor,source,action,target_type,target_id,detail"
    assert len(exported.splitlines()) == 2
    assert "order.cancel" in exported


def test_changes_made_in_the_admin_are_audited() -> None:
    admin = Client()
    admin.force_login(get_user_model().objects.create_superuser("root"))
    response = admin.post(
        "/admin/auth/group/add/", {"name": "operators"}, REMOTE_ADDR="192.168.1.5"
    )
    assert response.status_code == 302
    entry = AuditEntry.objects.get(action="admin.add")
    assert (entry.actor, entry.source, entry.target_type) == ("root", "192.168.1.5", "group")
    assert entry.detail["object"] == "operators"


def test_order_changes_and_vehicle_commands_are_audited_with_the_api_client(demo_map) -> None:
    from rest_framework.test import APIClient

    from orders.services import create_integration_client, issue_api_token
    from robots.models import Vehicle

    scopes = ["orders:write", "vehicles:command"]
    _, key = issue_api_token(client=create_integration_client(name="erp", scopes=scopes))
    api = APIClient()
    api.credentials(HTTP_AUTHORIZATION=f"Bearer {key}")
    created = api.post(
        "/api/v1/orders/",
        {"source": "PICK-1", "destination": "DROP-1", "external_ref": "SO-1"},
        format="json",
        REMOTE_ADDR="10.20.30.40",
    )
    assert created.status_code == 201, created.content
    order_id = created.json()["id"]
    assert (
        api.post(f"/api/v1/orders/{order_id}/cancel/", {"reason": "dup"}, format="json").status_code
        == 200
    )
    vehicle = Vehicle.objects.create(
        manufacturer="Acme", serial_number="AGV-1", connection="ONLINE"
    )
    assert api.post(f"/api/v1/vehicles/{vehicle.pk}/pause/").status_code in {200, 201, 202}

    entries = list(
        AuditEntry.objects.order_by("pk").values_list("actor", "source", "action", "target_id")
    )
    assert entries == [
        ("client:erp", "10.20.30.40", "order.create", str(order_id)),
        ("client:erp", "127.0.0.1", "order.cancel", str(order_id)),
        ("client:erp", "127.0.0.1", "vehicle.command", str(vehicle)),
    ]
