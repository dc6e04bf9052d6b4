"""The database side of parking idle vehicles: park stations reach control's layouts, and a
park request from traffic becomes a move to the station control chose, with its reason."""

from typing import Any

import pytest

from control.persistence import DjangoStore, _open_job
from maintenance.models import ServiceMove
from maps.models import Map
from robots.models import Vehicle

pytestmark = pytest.mark.django_db(transaction=True)  # the store closes stale connections


@pytest.fixture(autouse=True)
def sent_commands(monkeypatch: pytest.MonkeyPatch) -> list[tuple[str, dict[str, Any]]]:
    sent: list[tuple[str, dict[str, Any]]] = []
    monkeypatch.setattr(
        "maintenance.services.moves.send_command",
        lambda kind, **payload: sent.append((kind, payload)),
    )
    return sent


def parked_at(node: str) -> Vehicle:
    return Vehicle.objects.create(
        manufacturer="sim",
        serial_number="AGV-1",
        connection=Vehicle.Connection.ONLINE,
        operating_mode="AUTOMATIC",
        map_id="demo",
        last_node_id=node,
    )


def test_layouts_list_the_park_stations_and_their_nodes(demo_map: Map) -> None:
    layout = DjangoStore().load_layouts()["demo"]

    assert layout.parking == {f"PARK-{i}": f"S-PARK-{i}" for i in range(1, 5)}
    assert all(node in layout.nodes for node in layout.parking.values())


def test_a_park_request_from_traffic_opens_a_move_to_the_chosen_station(
    demo_map: Map, sent_commands: list[tuple[str, dict[str, Any]]]
) -> None:
    vehicle = parked_at("A0.0")

    _open_job(
        {
            "kind": "vehicle.park",
            "vehicle": vehicle.pk,
            "station": "PARK-3",  # not the nearest (PARK-1): control chose it
            "reason": "in the way of order TO-1",
        }
    )

    move = ServiceMove.objects.select_related("station").get(vehicle=vehicle)
    assert move.station.station_id == "PARK-3"
    assert move.reason == "in the way of order TO-1"
    assert move.route[0] == "A0.0"
    assert move.route[-1] == "S-PARK-3"
    assert [kind for kind, _ in sent_commands] == ["order.assigned"]
    (job,) = [o for o in DjangoStore().active_orders() if o.kind == "park"]
    assert (job.vehicle_pk, job.route) == (vehicle.pk, move.route)


def test_a_second_request_for_a_vehicle_already_on_its_way_is_refused_quietly(
    demo_map: Map,
) -> None:
    vehicle = parked_at("A0.0")
    job = {"kind": "vehicle.park", "vehicle": vehicle.pk, "station": "PARK-2", "reason": "x"}

    _open_job(job)
    _open_job(job | {"station": "PARK-4"})  # no command to report to: nothing raised

    assert ServiceMove.objects.filter(vehicle=vehicle).count() == 1
