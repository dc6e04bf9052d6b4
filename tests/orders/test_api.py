import pytest
from django.contrib.auth import get_user_model
from rest_framework.test import APIClient

from orders.models import TransportOrder


@pytest.fixture
def api(db: None) -> APIClient:
    client = APIClient()
    client.force_authenticate(get_user_model().objects.create_user("erp"))
    return client


def test_post_creates_an_order_by_station_ids(api, demo_map) -> None:
    response = api.post(
        "/api/v1/orders/",
        {"source": "PICK-1", "destination": "DROP-3", "load_id": "PAL-7"},
        format="json",
    )

    assert response.status_code == 201, response.content
    assert response.json()["status"] == "NEW"
    assert response.json()["events"][0]["kind"] == "CREATED"
    assert TransportOrder.objects.get().load_id == "PAL-7"


@pytest.mark.parametrize(
    ("body", "field"),
    [
        ({"source": "NOPE", "destination": "DROP-1"}, "source"),
        ({"source": "PICK-1"}, "destination"),
        ({"source": "PICK-1", "destination": "DROP-1", "priority": "high"}, "priority"),
    ],
)
def test_bad_input_gets_400_with_the_field_and_writes_nothing(api, demo_map, body, field) -> None:
    response = api.post("/api/v1/orders/", body, format="json")

    assert response.status_code == 400
    assert field in response.json()
    assert not TransportOrder.objects.exists()


def test_same_station_is_422_with_a_reason(api, demo_map) -> None:
    response = api.post(
        "/api/v1/orders/", {"source": "PICK-1", "destination": "PICK-1"}, format="json"
    )

    assert response.status_code == 422
    assert "same station" in response.json()["detail"]


def test_list_filters_by_status_and_cancel_of_a_closed_order_is_409(api, demo_map) -> None:
    created = api.post(
        "/api/v1/orders/", {"source": "PICK-1", "destination": "DROP-1"}, format="json"
    ).json()
    api.post(f"/api/v1/orders/{created['id']}/cancel/", {"reason": "test"}, format="json")

    cancelled = api.get("/api/v1/orders/?status=cancelled").json()
    again = api.post(f"/api/v1/orders/{created['id']}/cancel/", {}, format="json")

    assert [o["id"] for o in cancelled["results"]] == [created["id"]]
    assert again.status_code == 409


def test_anonymous_requests_are_refused(demo_map) -> None:
    assert APIClient().get("/api/v1/orders/").status_code in (401, 403)
