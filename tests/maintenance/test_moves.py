"""Sending vehicles to park stations: out of service, or by staff's park command; `control`
drives the move as an order without actions."""

import json
from typing import Any

import pytest

from control.controller import Controller
from control.execution import Progress
from control.persistence import DjangoStore, _apply, job_order_id
from fleet.exceptions import DomainError
from maintenance import selectors, services
from maintenance.models import ServiceMove
from orders.models import VehicleCommand
from tests.control.fakes import FakeStore, state, topic
from tests.factories import VehicleFactory

pytestmark = pytest.mark.django_db(transaction=True)  # the store closes stale connections


def test_out_of_service_vehicles_go_to_the_nearest_free_park_station(station: Any) -> None:
    first = VehicleFactory(last_node_id="A0.0")
    second = VehicleFactory(last_node_id="A0.0")
    VehicleFactory(last_node_id="S-PARK-2")  # stands on PARK-2: not free

    services.take_out_of_service(vehicle=first, reason="noise", send_to="PARK")
    services.take_out_of_service(vehicle=second, reason="noise", send_to="PARK")

    moves = {m.vehicle_id: m for m in ServiceMove.objects.select_related("station")}
    assert moves[first.pk].station.station_id == "PARK-1"
    assert moves[first.pk].route == ["A0.0", "S-PARK-1"]
    assert moves[second.pk].station.station_id == "PARK-3"  # PARK-1 taken, PARK-2 occupied
    assert moves[first.pk].reason == "out of service: noise"


def test_a_failed_send_leaves_the_vehicle_in_service(station: Any) -> None:
    vehicle = VehicleFactory(last_node_id="A0.0")
    with pytest.raises(DomainError, match="no free other station"):
        services.take_out_of_service(vehicle=vehicle, reason="noise", send_to="OTHER")
    assert selectors.out_of_service(vehicle_ids=[vehicle.pk]) == {}


def test_control_drives_a_move_as_an_order_and_it_ends_on_arrival(station: Any) -> None:
    vehicle = VehicleFactory(last_node_id="A0.0")
    move = services.send_to_station(vehicle=vehicle)
    (job,) = [o for o in DjangoStore().active_orders() if o.kind == "park"]
    assert (job.transport_order_id, job.vda_order_id) == (
        job_order_id("park", move.pk),
        move.vda_order_id,
    )
    assert job.route == ["A0.0", "S-PARK-1"]

    sent: list[tuple[str, dict[str, Any]]] = []
    controller = Controller(
        store=FakeStore(),
        interface_name="uagv",
        publish=lambda t, payload, qos: sent.append((t, json.loads(payload))),
    )
    controller.load()
    controller.handle_message(topic(), state(last_node="a"))
    controller.sync(
        [type(job)(**{**job.__dict__, "vehicle_pk": 1, "route": ["a", "b"], "pickup_node": "b"})]
    )
    (message,) = [m for t, m in sent if t.endswith("/order")]
    assert [n["actions"] for n in message["nodes"]] == [[], []]
    controller.handle_message(topic(), state(header_id=2, order_id=job.vda_order_id, last_node="b"))
    controller.flush()
    kinds = [p.kind for p in controller.store.batches[-1].progress]
    assert kinds == ["sent", "started", "finished"]

    for kind in kinds:
        _apply(Progress(kind, job.transport_order_id))
    move.refresh_from_db()
    assert move.status == ServiceMove.Status.DONE
    assert selectors.list_move_jobs() == []


def test_the_park_command_becomes_a_move(station: Any) -> None:
    vehicle = VehicleFactory(last_node_id="A0.2")
    command = VehicleCommand.objects.create(vehicle=vehicle, kind="vehicle.park")
    controller = Controller(store=DjangoStore(), interface_name="uagv", publish=lambda *a: None)
    controller.load()

    controller.execute({"kind": "vehicle.park", "vehicle": vehicle.pk, "command": command.pk})
    controller.flush()

    command.refresh_from_db()
    assert (command.status, command.result) == ("RUNNING", "on its way to PARK-3")
    assert ServiceMove.objects.get().command_id == command.pk
