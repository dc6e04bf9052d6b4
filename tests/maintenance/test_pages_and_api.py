"""Staff pages and the read API of the maintenance app."""

from typing import Any

import pytest
from django.core.files.uploadedfile import SimpleUploadedFile
from django.test import Client
from rest_framework.test import APIClient

from maintenance import services
from maintenance.models import ErrorRecord, ServiceEvent, ServiceMove, WorkOrder
from tests.factories import VehicleFactory, user_with_role

pytestmark = pytest.mark.django_db


@pytest.fixture
def staff(django_user_model: Any) -> Any:
    return user_with_role("technician", "tech", password="x")


@pytest.fixture
def viewer(django_user_model: Any) -> Any:
    return user_with_role("manager", "viewer", password="x")  # reads, changes nothing


def test_staff_take_a_vehicle_out_of_service_and_back_from_its_page(
    client: Client, staff: Any, demo_map: Any
) -> None:
    vehicle = VehicleFactory(serial_number="AGV-9")
    client.force_login(staff)
    url = f"/maintenance/vehicles/{vehicle.pk}/service/"

    client.post(url, {"action": "out", "reason": "bumper cracked"})
    page = client.get(f"/maintenance/vehicles/{vehicle.pk}/").content.decode()
    assert "out of service: bumper cracked" in page
    assert "Return to service" in page

    client.post(url, {"action": "back"})
    client.post(url, {"action": "out", "reason": "wheel", "send_to": "PARK"})
    assert ServiceMove.objects.get(vehicle=vehicle).station.station_id == "PARK-1"
    client.post(url, {"action": "back"})
    kinds = list(ServiceEvent.objects.order_by("pk").values_list("kind", flat=True))
    assert kinds == ["OUT_OF_SERVICE", "BACK_IN_SERVICE"] * 2
    response = client.post(url, {"action": "back"}, follow=True)
    assert "is in service" in response.content.decode()  # refused with the reason


def test_viewers_read_but_do_not_change(client: Client, viewer: Any) -> None:
    vehicle = VehicleFactory()
    client.force_login(viewer)
    assert client.get("/maintenance/").status_code == 200
    response = client.post(f"/maintenance/vehicles/{vehicle.pk}/service/", {"action": "back"})
    assert response.status_code == 403
    assert client.get("/maintenance/").status_code == 200


def test_a_work_order_is_advanced_with_notes_parts_and_a_file(
    client: Client, staff: Any, settings: Any, tmp_path: Any
) -> None:
    settings.MEDIA_ROOT = str(tmp_path)
    work_order = services.create_work_order(
        vehicle=VehicleFactory(), title="Brake check", takes_out_of_service=True
    )
    client.force_login(staff)
    url = f"/maintenance/work-orders/{work_order.pk}/"

    client.post(url, {"status": "IN_PROGRESS", "notes": "pads at 2 mm"})
    client.post(
        url,
        {
            "status": "DONE",
            "part": "brake pad",
            "quantity": "2",
            "attachment": SimpleUploadedFile("report.txt", b"ok"),
        },
    )

    work_order.refresh_from_db()
    assert work_order.status == WorkOrder.Status.DONE
    assert work_order.parts == [{"part": "brake pad", "qty": 2}]
    assert "pads at 2 mm" in work_order.notes
    assert work_order.attachments.count() == 1
    page = client.get(url).content.decode()
    assert "2 × brake pad" in page
    overview = client.get("/maintenance/").content.decode()
    assert "Nothing due." in overview


def test_the_api_reads_plans_work_orders_counters_history_and_errors(staff: Any) -> None:
    vehicle = VehicleFactory()
    work_order = services.create_work_order(
        vehicle=vehicle, title="Squeaks", takes_out_of_service=True
    )
    ErrorRecord.objects.create(
        vehicle=vehicle, error_type="motorFault", error_level="FATAL", started_at=work_order.due_at
    )
    services.take_out_of_service(vehicle=vehicle, reason="waiting for parts")
    api = APIClient()
    api.force_authenticate(staff)

    (listed,) = api.get("/api/v1/maintenance/work-orders/?status=OPEN").json()["results"]
    assert (listed["id"], listed["title"]) == (work_order.pk, "Squeaks")
    assert api.get("/api/v1/maintenance/work-orders/?status=DONE").json()["results"] == []
    (counters,) = api.get("/api/v1/maintenance/vehicles/").json()["results"]
    assert counters["out_of_service_reason"] == "waiting for parts"
    history = api.get(f"/api/v1/maintenance/vehicles/{vehicle.pk}/history/").json()["results"]
    assert [h["kind"] for h in history] == ["OUT_OF_SERVICE", "OUT_OF_SERVICE"]
    errors = api.get(f"/api/v1/maintenance/vehicles/{vehicle.pk}/errors/").json()
    assert errors["stats"]["top_types"] == [["motorFault", 1]]
    assert errors["reasons_unavailable"] == "out of service: waiting for parts"
    assert api.get("/api/v1/maintenance/plans/").json()["results"] == []
    assert api.get("/api/v1/maintenance/vehicles/999999/errors/").status_code == 404
