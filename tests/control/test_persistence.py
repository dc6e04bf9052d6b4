"""The database side of control: a flush writes snapshots, order progress and command outcomes."""

import pytest

from control.controller import Controller
from control.execution import OrderExecution, Progress, Window
from control.order_messages import LoadJob, build_order
from control.persistence import DjangoStore, job_order_id
from control.ports import FlushBatch
from maintenance.services import send_to_station
from maps.models import Station
from maps.services import create_zone
from orders import selectors, services
from orders.models import TransportOrder, VehicleCommand, WebhookDelivery
from robots.models import Vehicle
from tests.control.fakes import state
from tests.factories import VehicleFactory
from tests.maps.zones_support import box

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
    assert "has no known position" in command.result  # issue 7: parking needs a position


def test_a_speed_zone_lowers_max_speed_in_the_sent_order(demo_map) -> None:
    """Issue 4: zones change speeds in the orders control sends."""
    create_zone(
        map=demo_map,
        zone_id="slow",
        zone_type="SPEED_LIMIT",
        max_speed=0.4,
        vertices=box(3.5, -1, 5.5, 1),
    )  # only over the aisle edge A1.0 - A2.0
    layouts = DjangoStore().load_layouts()
    execution = OrderExecution.plan(
        transport_order_id=1,
        vda_order_id="TO-1",
        route=["A0.0", "A1.0", "A2.0", "A3.0"],
        pickup="A1.0",
    )

    nodes, edges = build_order(
        execution, layouts["demo"], Window(0, 3, 3), LoadJob("", "EPAL", "P", "D"), max_speed=True
    )
    _, unlimited = build_order(
        execution, layouts["demo"], Window(0, 3, 3), LoadJob("", "EPAL", "P", "D"), max_speed=False
    )

    assert [e.max_speed for e in edges] == [None, 0.4, None]
    assert [e.max_speed for e in unlimited] == [None, None, None]


def test_the_store_reads_the_orders_a_command_names_and_only_those(demo_map, monkeypatch) -> None:
    """Issue 11: `order.assigned` names its orders; control reads those rows, not all."""
    for module in ("orders.services.dispatch", "maintenance.services.moves"):
        monkeypatch.setattr(f"{module}.send_command", lambda kind, **payload: None)
    vehicles = [VehicleFactory(last_node_id=f"A{n}.0") for n in range(3)]
    pick, drop = (Station.objects.get(station_id=s) for s in ("PICK-1", "DROP-1"))
    named, other = (services.create_transport_order(source=pick, destination=drop) for _ in "ab")
    services.dispatch_pending_orders()
    done = services.create_transport_order(source=pick, destination=drop)
    done.status = TransportOrder.Status.FINISHED
    done.save()
    move = send_to_station(vehicle=vehicles[2])
    store = DjangoStore()

    found = store.assigned_orders(orders=[named.pk, done.pk], charge_sessions=[], moves=[move.pk])

    every = {o.transport_order_id: o for o in store.active_orders()}
    assert set(every) == {named.pk, other.pk, job_order_id("park", move.pk)}
    assert found == [every[named.pk], every[job_order_id("park", move.pk)]]
    assert store.assigned_orders(orders=[], charge_sessions=[move.pk], moves=[]) == []


def test_a_flush_reads_the_webhook_subscriptions_once_and_still_records_every_event(
    demo_map, monkeypatch
) -> None:
    """Issue 11: each order event asked for the subscriptions (a query per event); a flush
    now reads them once for all its progress, and the subscriber still gets every event."""
    monkeypatch.setattr("orders.services.dispatch.send_command", lambda kind, **payload: None)
    erp = services.create_integration_client(name="erp", scopes=["orders:read"])
    services.create_webhook_subscription(client=erp, url="http://127.0.0.1:9/", events=["*"])
    VehicleFactory(last_node_id="A0.0")
    pick, drop = (Station.objects.get(station_id=s) for s in ("PICK-1", "DROP-1"))
    order = services.create_transport_order(source=pick, destination=drop)
    services.dispatch_pending_orders()
    batch = FlushBatch(
        progress=[
            Progress("started", order.pk),
            Progress("step", order.pk, {"step": "pick", "node": "S-PICK-1", "index": "0"}),
            Progress("step", order.pk, {"step": "drop", "node": "S-DROP-1", "index": "1"}),
            Progress("finished", order.pk),
        ]
    )
    before = WebhookDelivery.objects.count()
    reads = []
    real = selectors.list_active_subscriptions
    monkeypatch.setattr(selectors, "list_active_subscriptions", lambda: reads.append(1) or real())

    DjangoStore().flush(batch)

    order.refresh_from_db()
    assert order.status == TransportOrder.Status.FINISHED
    assert len(reads) == 1
    recorded = WebhookDelivery.objects.order_by("pk")[before:]
    assert sorted(d.event_type for d in recorded) == sorted(
        [
            "order.started",
            "order.step_reached",
            "order.step_reached",
            "order.finished",
            "vehicle.order_finished",
        ]
    )
