"""Charge sessions driven by `control`: an order to the charging point ending in startCharging,
its progress back into the session, and staff's charge command becoming a session."""

import json
from typing import Any

import pytest

from battery import services
from battery.models import Charger, ChargeSession
from control.controller import Controller
from control.execution import Progress
from control.persistence import DjangoStore, _apply, job_order_id
from control.ports import ActiveOrder
from orders.models import VehicleCommand
from tests.control.fakes import FakeStore, state, topic
from tests.factories import VehicleFactory

Status = ChargeSession.Status
pytestmark = pytest.mark.django_db(transaction=True)  # the store closes stale connections


def published() -> tuple[list[tuple[str, dict[str, Any]]], Any]:
    sent: list[tuple[str, dict[str, Any]]] = []
    return sent, lambda t, payload, qos: sent.append((t, json.loads(payload)))


def test_a_charge_job_is_an_order_that_ends_in_start_charging_at_the_point() -> None:
    sent, publish = published()
    controller = Controller(store=FakeStore(), interface_name="uagv", publish=publish)
    controller.load()
    controller.handle_message(topic(), state(last_node="a"))
    job = ActiveOrder(
        transport_order_id=-3,
        vda_order_id="CS-3",
        vehicle_pk=1,
        route=["a", "b"],
        pickup_node="b",
        map_id="demo",
        pick_station="CHARGE-1",
        drop_station="CHARGE-1",
        kind="charge",
    )

    controller.sync([job])

    (message,) = [m for t, m in sent if t.endswith("/order")]
    assert message["orderId"] == "CS-3"
    assert [n["actions"] for n in message["nodes"]][0] == []
    (action,) = message["nodes"][-1]["actions"]
    assert (action["actionType"], action["actionId"], action["blockingType"]) == (
        "startCharging",
        "CS-3-charge",
        "HARD",
    )
    controller.handle_message(
        topic(),
        state(header_id=2, order_id="CS-3", last_node="b", actions=(("CS-3-charge", "FINISHED"),)),
    )
    controller.flush()
    progress = [
        (p.kind, p.order_id, p.detail.get("step")) for p in controller.store.batches[-1].progress
    ]
    assert progress == [
        ("sent", -3, None),
        ("started", -3, None),
        ("step", -3, "charge"),
        ("finished", -3, None),
    ]


def test_the_store_lists_charge_jobs_and_applies_their_progress(chargers: list[Charger]) -> None:
    vehicle = VehicleFactory(battery_charge=20.0, last_node_id="A5.1")
    services.plan_charging(work_waiting=True)
    session = ChargeSession.objects.get(vehicle=vehicle)

    (job,) = [o for o in DjangoStore().active_orders() if o.kind == "charge"]
    assert (job.transport_order_id, job.vda_order_id, job.vehicle_pk) == (
        job_order_id("charge", session.pk),
        f"CS-{session.pk}",
        vehicle.pk,
    )
    assert job.route == ["A5.1", "S-CHARGE-1"]
    assert job.pickup_node == "S-CHARGE-1"

    _apply(Progress("sent", job_order_id("charge", session.pk)))
    _apply(
        Progress(
            "step", job_order_id("charge", session.pk), {"step": "charge", "node": "S-CHARGE-1"}
        )
    )
    session.refresh_from_db()
    assert session.status == Status.CHARGING
    assert session.started_at is not None
    assert [o for o in DjangoStore().active_orders() if o.kind == "charge"] == []


def test_a_failed_charge_job_frees_its_point(chargers: list[Charger]) -> None:
    vehicle = VehicleFactory(battery_charge=20.0, last_node_id="A5.1")
    services.plan_charging(work_waiting=True)
    session = ChargeSession.objects.get(vehicle=vehicle)
    _apply(
        Progress("failed", job_order_id("charge", session.pk), {"reason": "rejected by vehicle"})
    )
    session.refresh_from_db()
    assert (session.status, session.note) == (Status.FAILED, "rejected by vehicle")


def test_staff_charge_command_becomes_a_session(chargers: list[Charger]) -> None:
    vehicle = VehicleFactory()
    command = VehicleCommand.objects.create(vehicle=vehicle, kind="vehicle.charge")
    controller = Controller(store=DjangoStore(), interface_name="uagv", publish=lambda *a: None)
    controller.load()
    controller.execute(
        {"kind": "vehicle.charge", "vehicle": vehicle.pk, "command": command.pk, "station": ""}
    )
    controller.flush()

    session = ChargeSession.objects.get(vehicle=vehicle)
    command.refresh_from_db()
    assert (session.reason, session.command_id) == ("MANUAL", command.pk)
    assert command.status == VehicleCommand.Status.RUNNING
    assert f"charge session {session.pk} queued" in command.result

    again = VehicleCommand.objects.create(vehicle=vehicle, kind="vehicle.charge")
    controller.execute({"kind": "vehicle.charge", "vehicle": vehicle.pk, "command": again.pk})
    controller.flush()
    again.refresh_from_db()
    assert again.status == VehicleCommand.Status.REFUSED
    assert "already has a charge session" in again.result
