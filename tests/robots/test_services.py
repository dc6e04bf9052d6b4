import pytest

from robots.models import Vehicle
from robots.services import register_vehicles, save_factsheets, save_snapshots

pytestmark = pytest.mark.django_db


def test_registration_is_idempotent_and_returns_every_id() -> None:
    first = register_vehicles(identities=[("acme", "A1"), ("acme", "A2")])
    again = register_vehicles(identities=[("acme", "A2"), ("other", "A1")])

    assert first[("acme", "A2")] == again[("acme", "A2")]
    assert set(again) == {("acme", "A2"), ("other", "A1")}
    assert Vehicle.objects.count() == 3


def test_snapshots_are_written_in_bulk_and_leave_registry_fields_alone() -> None:
    ids = register_vehicles(identities=[("acme", "A1"), ("acme", "A2")])
    Vehicle.objects.filter(pk=ids[("acme", "A1")]).update(name="Forklift one")
    base = {
        "connection": "ONLINE",
        "protocol_version": "2.1.0",
        "interface_name": "uagv",
        "map_id": "demo",
        "x": 1.0,
        "y": 2.0,
        "theta": 0.5,
        "position_initialized": True,
        "battery_charge": 55.0,
        "charging": False,
        "driving": True,
        "paused": False,
        "operating_mode": "AUTOMATIC",
        "errors": [],
        "loads": [{"loadId": "L"}],
        "order_id": "TO-1",
        "order_update_id": 0,
        "last_node_id": "n1",
        "last_node_sequence_id": 2,
        "last_seen": None,
    }

    written = save_snapshots(snapshots=[{**base, "pk": pk} for pk in ids.values()])
    save_factsheets(factsheets={ids[("acme", "A2")]: {"version": "2.1.0"}})

    one = Vehicle.objects.get(pk=ids[("acme", "A1")])
    assert written == 2
    assert (one.name, one.battery_charge, one.loads) == ("Forklift one", 55.0, [{"loadId": "L"}])
    assert Vehicle.objects.get(pk=ids[("acme", "A2")]).factsheet == {"version": "2.1.0"}


def test_availability_needs_connection_mode_position_and_no_fatal_error() -> None:
    ok = Vehicle(connection="ONLINE", operating_mode="AUTOMATIC", last_node_id="n1")
    assert ok.is_available
    for change in (
        {"connection": "CONNECTIONBROKEN"},
        {"operating_mode": "MANUAL"},
        {"last_node_id": ""},
        {"paused": True},
        {"errors": [{"errorType": "x", "errorLevel": "FATAL"}]},
    ):
        vehicle = Vehicle(
            **{
                "connection": "ONLINE",
                "operating_mode": "AUTOMATIC",
                "last_node_id": "n1",
                **change,
            }
        )
        assert not vehicle.is_available, change
