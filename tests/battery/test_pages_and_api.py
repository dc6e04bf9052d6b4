"""Staff pages and the read API of the battery app."""

from typing import Any

import pytest
from django.test import Client
from rest_framework.test import APIClient

from battery.models import Charger, ChargeSession
from battery.services.observe import EnergyObserver
from tests.factories import VehicleFactory, user_with_role


@pytest.fixture
def staff(django_user_model: Any) -> Any:
    return user_with_role("technician", "tech", password="x")


def test_pages_need_a_login(client: Client, db: None) -> None:
    for url in ("/energy/", "/energy/vehicles/1/"):
        response = client.get(url)
        assert response.status_code == 302
        assert "login" in response["Location"]


def test_the_overview_shows_batteries_chargers_and_sessions(
    client: Client, staff: Any, chargers: list[Charger]
) -> None:
    vehicle = VehicleFactory(battery_charge=12.0, serial_number="LOW-1")
    ChargeSession.objects.create(vehicle=vehicle, reason="CRITICAL")
    EnergyObserver().observe(
        [{"pk": vehicle.pk, "battery_charge": 12.0, "charging": False}], now=0.0
    )
    client.force_login(staff)

    page = client.get("/energy/").content.decode()

    assert "LOW-1" in page
    assert "CRITICAL" in page  # band and reason
    assert "CHARGE-1" in page
    assert "CHARGE-2" in page
    assert f"CS-{ChargeSession.objects.get().pk}" in page
    detail = client.get(f"/energy/vehicles/{vehicle.pk}/").content.decode()
    assert "12.0" in detail


def test_the_api_reads_batteries_history_chargers_and_sessions(
    staff: Any, chargers: list[Charger]
) -> None:
    vehicle = VehicleFactory(battery_charge=50.0)
    ChargeSession.objects.create(
        vehicle=vehicle, charger=chargers[0], point=0, status="CHARGING", reason="LOW"
    )
    EnergyObserver().observe([{"pk": vehicle.pk, "battery_charge": 50.0}], now=0.0)
    api = APIClient()
    api.force_authenticate(staff)

    (row,) = api.get("/api/v1/battery/vehicles/").json()["results"]
    assert (row["vehicle"], row["battery_charge"], row["band"]) == (vehicle.pk, 50.0, "WORKING")
    assert row["session_status"] == "CHARGING"
    history = api.get(f"/api/v1/battery/vehicles/{vehicle.pk}/history/").json()["results"]
    assert [h["charge"] for h in history] == [50.0]
    listed = api.get("/api/v1/battery/chargers/").json()["results"]
    assert [c["station_id"] for c in listed] == ["CHARGE-1", "CHARGE-2"]
    assert listed[0]["booked_points"] == [{"point": 0, "vehicle": vehicle.pk}]
    sessions = api.get("/api/v1/battery/sessions/?status=CHARGING").json()["results"]
    assert [s["charger_station"] for s in sessions] == ["CHARGE-1"]
    assert api.get("/api/v1/battery/sessions/?status=NOPE").status_code == 400
    assert api.get("/api/v1/battery/vehicles/999999/history/").status_code == 404
    assert APIClient().get("/api/v1/battery/vehicles/").status_code in {401, 403}
