"""The vehicle read API."""

import pytest
from rest_framework.test import APIClient

from tests.factories import VehicleFactory, user_with_role

pytestmark = pytest.mark.django_db


@pytest.fixture
def api() -> APIClient:
    client = APIClient()
    client.force_authenticate(user_with_role("operator", "viewer"))
    return client


def test_list_shows_state_and_availability_with_filters(api) -> None:
    ready = VehicleFactory(serial_number="A-1", manufacturer="acme")
    VehicleFactory(serial_number="B-1", manufacturer="other", connection="OFFLINE")
    VehicleFactory(serial_number="C-1", manufacturer="acme", map_id="hall-2", paused=True)

    everything = api.get("/api/v1/vehicles/").json()
    online = api.get("/api/v1/vehicles/?connection=ONLINE").json()
    acme_hall_2 = api.get("/api/v1/vehicles/?manufacturer=acme&map_id=hall-2").json()

    assert everything["count"] == 3
    first = everything["results"][0]
    assert (first["id"], first["serial_number"], first["available"]) == (ready.pk, "A-1", True)
    assert {"battery_charge", "last_node_id", "errors", "loads", "paused"} <= set(first)
    assert [v["serial_number"] for v in online["results"]] == ["A-1", "C-1"]
    assert [(v["serial_number"], v["available"]) for v in acme_hall_2["results"]] == [
        ("C-1", False)
    ]
    assert api.get("/api/v1/vehicles/?connection=SOMETIMES").status_code == 400


def test_detail_and_404s(api) -> None:
    vehicle = VehicleFactory()

    assert api.get(f"/api/v1/vehicles/{vehicle.pk}/").json()["serial_number"] == (
        vehicle.serial_number
    )
    assert api.get("/api/v1/vehicles/424242/").status_code == 404
    assert api.get("/api/v1/vehicles/9999999999999999999999/").status_code == 404
    assert api.get("/api/v1/vehicles/abc/").status_code == 404


def test_vehicles_are_read_only_here(api) -> None:
    vehicle = VehicleFactory()

    assert api.post("/api/v1/vehicles/", {}, format="json").status_code == 405
    assert api.patch(f"/api/v1/vehicles/{vehicle.pk}/", {}, format="json").status_code == 405


def test_anonymous_is_refused(db) -> None:
    assert APIClient().get("/api/v1/vehicles/").status_code == 401
