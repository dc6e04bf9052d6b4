"""The ERP's "where is load L" / "move load L to S", and CSV import/export of the inventory."""

import pytest
from rest_framework.test import APIClient

from fleet.roles import assign_role
from inventory import services
from inventory.models import LoadCarrier, Movement, StorageLocation
from maps.models import Map, Station
from orders import services as order_services
from orders.models import TransportOrder
from tests.factories import user_with_role

pytestmark = pytest.mark.django_db


@pytest.fixture
def api(db: None) -> APIClient:
    client = APIClient()
    erp = order_services.create_integration_client(
        name="erp", scopes=["loads:read", "loads:write", "orders:read"]
    )
    client.credentials(HTTP_AUTHORIZATION=f"Bearer {order_services.issue_api_token(client=erp)[1]}")
    return client


@pytest.fixture
def stocked(demo_map: Map) -> Map:
    for station in Station.objects.filter(kind__in=["PICK", "DROP"]):
        services.define_location(station=station, capacity=2)
    load = services.register_load(load_id="L1", weight=420.0)
    services.move_load(
        load=load, location=StorageLocation.objects.get(station__station_id="PICK-1")
    )
    services.register_load(load_id="NOWHERE")
    return demo_map


def test_the_erp_asks_where_a_load_is(api, stocked) -> None:
    answer = api.get("/api/v1/loads/L1/")

    assert answer.status_code == 200
    assert answer.json()["place"] == "STATION"
    assert answer.json()["station"] == "PICK-1"
    assert answer.json()["slot"] == 1
    assert api.get("/api/v1/loads/NOPE/").status_code == 404
    assert APIClient().get("/api/v1/loads/L1/").status_code in (401, 403)


def test_the_erp_moves_a_load_and_the_system_finds_the_source(api, stocked) -> None:
    answer = api.post(
        "/api/v1/loads/L1/move/", {"station": "DROP-2", "external_ref": "ERP-9"}, format="json"
    )

    assert answer.status_code == 201, answer.content
    order = TransportOrder.objects.get(pk=answer.json()["id"])
    assert order.source.station_id == "PICK-1"
    assert order.destination.station_id == "DROP-2"
    assert order.load_id == "L1"


@pytest.mark.parametrize(
    ("load", "body", "status"),
    [
        ("L1", {"station": "NO-SUCH"}, 400),
        ("L1", {"station": "PICK-1"}, 422),  # already there
        ("NOWHERE", {"station": "DROP-1"}, 422),  # not at a station
        ("L1", {}, 400),
    ],
)
def test_a_bad_move_is_refused_and_creates_nothing(api, stocked, load, body, status) -> None:
    answer = api.post(f"/api/v1/loads/{load}/move/", body, format="json")

    assert answer.status_code == status
    assert TransportOrder.objects.count() == 0


def test_locations_and_stock_round_trip_through_csv(stocked) -> None:
    locations, stock = services.export_csv("locations"), services.export_csv("stock")
    assert "PICK-1" in locations
    assert "L1,EPAL,demo,PICK-1,1" in stock

    LoadCarrier.objects.all().delete()
    StorageLocation.objects.all().delete()
    assert services.import_csv("locations", locations) == 8  # 4 pick + 4 drop stations
    assert services.import_csv("stock", stock) == 2

    assert services.export_csv("locations") == locations
    assert services.export_csv("stock") == stock
    assert Movement.objects.filter(reason=Movement.Reason.IMPORT).count() == 1


@pytest.mark.parametrize(
    "text",
    [
        "map_id,station_id,capacity\ndemo,PICK-1,3\ndemo,NO-SUCH,1\n",
        "map_id,station_id,capacity\ndemo,PICK-1,0\n",
        "map_id,station,capacity\ndemo,PICK-1,1\n",
        "map_id,station_id,capacity\ndemo,PICK-1,lots\n",
    ],
)
def test_a_bad_csv_row_rejects_the_whole_file(stocked, text) -> None:
    before = services.export_csv("locations")
    with pytest.raises(Exception, match="line|column|capacity"):
        services.import_csv("locations", text)
    assert services.export_csv("locations") == before


def test_staff_import_stock_on_the_page_and_others_cannot(
    client, stocked, django_user_model
) -> None:
    csv = b"load_id,load_type,map_id,station_id,slot\nL7,EPAL,demo,DROP-1,\n"
    user = user_with_role("operator", "clerk", password="pw")  # sees stock, imports nothing
    client.force_login(user)
    assert client.get("/inventory/").status_code == 200
    from django.core.files.uploadedfile import SimpleUploadedFile

    client.post("/inventory/stock/import/", {"file": SimpleUploadedFile("s.csv", csv)})
    assert not LoadCarrier.objects.filter(load_id="L7").exists()

    assign_role(user=user, role="administrator")
    client.post("/inventory/stock/import/", {"file": SimpleUploadedFile("s.csv", csv)})
    assert LoadCarrier.objects.get(load_id="L7").location.station.station_id == "DROP-1"
    assert client.get("/inventory/stock.csv").content.decode().count("\n") == 4
