"""The database side of control: a flush writes snapshots, order progress and command outcomes."""

import pytest

from control.controller import Controller
from control.persistence import DjangoStore
from orders import services
from orders.models import VehicleCommand
from robots.models import Vehicle
from tests.control.fakes import state

pytestmark = pytest.mark.django_db(transaction=True)  # the store closes stale connections


def test_a_flush_records_the_outcome_of_an_operator_command() -> None:
    vehicle = Vehicle.objects.create(
        manufacturer="sim", serial_number="AGV-1", connection=Vehicle.Connection.ONLINE
    )
    command = services.pause_vehicle(vehicle=vehicle)
    controller = Controller(store=DjangoStore(), interface_name="uagv", publish=lambda *a: None)
    controller.load()
    controller.handle_message("uagv/v2/sim/AGV-1/state", state(header_id=1))

    controller.execute({"kind": "vehicle.pause", "vehicle": vehicle.pk, "command": command.pk})
    controller.flush()
    command.refresh_from_db()
    sent_status, action_id = command.status, command.action_id
    controller.handle_message(
        "uagv/v2/sim/AGV-1/state", state(header_id=2, actions=((action_id, "FINISHED"),))
    )
    controller.flush()
    command.refresh_from_db()

    assert sent_status == VehicleCommand.Status.SENT
    assert command.status == VehicleCommand.Status.FINISHED
    vehicle.refresh_from_db()
    assert vehicle.last_node_id == "a"


def test_a_refused_command_keeps_its_reason() -> None:
    vehicle = Vehicle.objects.create(
        manufacturer="sim", serial_number="AGV-1", connection=Vehicle.Connection.ONLINE
    )
    command = VehicleCommand.objects.create(vehicle=vehicle, kind="vehicle.park")
    controller = Controller(store=DjangoStore(), interface_name="uagv", publish=lambda *a: None)
    controller.load()
    controller.handle_message("uagv/v2/sim/AGV-1/state", state(header_id=1))

    controller.execute({"kind": "vehicle.park", "vehicle": vehicle.pk, "command": command.pk})
    controller.flush()

    command.refresh_from_db()
    assert command.status == VehicleCommand.Status.REFUSED
    assert "not supported yet" in command.result
