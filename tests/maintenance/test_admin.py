"""The admin pages of the battery and maintenance apps open for staff."""

from typing import Any

import pytest
from django.test import Client

from battery.models import Charger, ChargeSession
from maintenance import services
from maps.models import Station
from tests.factories import VehicleFactory

PAGES = [
    "battery/charger",
    "battery/chargingpolicy",
    "battery/chargesession",
    "battery/vehicleenergy",
    "battery/batterysample",
    "battery/batteryalert",
    "maintenance/serviceplan",
    "maintenance/workorder",
    "maintenance/vehiclecounters",
    "maintenance/serviceevent",
    "maintenance/errorrecord",
    "maintenance/servicemove",
]


@pytest.mark.parametrize("page", PAGES)
def test_changelists_open(admin_client: Client, demo_map: Any, page: str) -> None:
    vehicle = VehicleFactory()
    charger = Charger.objects.create(station=Station.objects.get(station_id="CHARGE-1"))
    ChargeSession.objects.create(vehicle=vehicle, charger=charger, point=0, reason="LOW")
    services.create_work_order(vehicle=vehicle, title="Check", takes_out_of_service=True)
    assert admin_client.get(f"/admin/{page}/").status_code == 200


def test_a_charger_is_offered_only_charge_stations(admin_client: Client, demo_map: Any) -> None:
    form = admin_client.get("/admin/battery/charger/add/").content.decode()
    assert "CHARGE-1" in form
    assert "PICK-1" not in form
