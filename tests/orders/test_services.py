import pytest
from django.db import IntegrityError

from fleet.exceptions import DomainError, InvalidRequestError
from maps.models import Station
from orders import services
from orders.models import OrderEvent, TransportOrder
from tests.factories import VehicleFactory


def station(demo_map, station_id: str) -> Station:
    return Station.objects.get(map=demo_map, station_id=station_id)


def test_create_queues_an_order_with_a_created_event(demo_map) -> None:
    order = services.create_transport_order(
        source=station(demo_map, "PICK-1"), destination=station(demo_map, "DROP-2"), load_id="L1"
    )

    assert order.status == TransportOrder.Status.NEW
    assert list(order.events.values_list("kind", flat=True)) == [OrderEvent.Kind.CREATED]


def test_create_refuses_the_same_station_twice(demo_map) -> None:
    pick = station(demo_map, "PICK-1")
    with pytest.raises(InvalidRequestError):
        services.create_transport_order(source=pick, destination=pick)
    assert not TransportOrder.objects.exists()


def test_dispatch_assigns_the_nearest_idle_vehicle_with_a_route_via_the_source(demo_map) -> None:
    far = VehicleFactory(last_node_id="A0.0")
    near = VehicleFactory(last_node_id="A1.3")  # next to PICK-1's aisle node
    order = TransportOrder.objects.create(
        source=station(demo_map, "PICK-1"), destination=station(demo_map, "DROP-4")
    )

    assigned = services.dispatch_pending_orders()

    order.refresh_from_db()
    assert assigned == [order]
    assert order.vehicle == near
    assert order.status == TransportOrder.Status.ASSIGNED
    assert order.route[0] == "A1.3"
    assert order.route[-1] == "S-DROP-4"
    assert "S-PICK-1" in order.route
    assert order.vda_order_id == f"TO-{order.pk}"
    assert far.transport_orders.count() == 0


def test_dispatch_skips_unavailable_vehicles(demo_map) -> None:
    VehicleFactory(connection="OFFLINE")
    VehicleFactory(operating_mode="MANUAL")
    VehicleFactory(errors=[{"errorType": "x", "errorLevel": "FATAL"}])
    VehicleFactory(last_node_id="")
    TransportOrder.objects.create(
        source=station(demo_map, "PICK-1"), destination=station(demo_map, "DROP-1")
    )

    assert services.dispatch_pending_orders() == []


def test_dispatch_gives_one_order_per_vehicle_most_urgent_first(demo_map) -> None:
    VehicleFactory()
    low = TransportOrder.objects.create(
        source=station(demo_map, "PICK-1"), destination=station(demo_map, "DROP-1")
    )
    high = TransportOrder.objects.create(
        source=station(demo_map, "PICK-2"), destination=station(demo_map, "DROP-2"), priority=5
    )

    assert services.dispatch_pending_orders() == [high]
    assert services.dispatch_pending_orders() == []  # the vehicle is busy now
    low.refresh_from_db()
    assert low.status == TransportOrder.Status.NEW


def test_database_refuses_two_active_orders_for_one_vehicle(demo_map) -> None:
    vehicle = VehicleFactory()
    common = {
        "source": station(demo_map, "PICK-1"),
        "destination": station(demo_map, "DROP-1"),
        "vehicle": vehicle,
        "status": TransportOrder.Status.ASSIGNED,
    }
    TransportOrder.objects.create(**common)
    with pytest.raises(IntegrityError):
        TransportOrder.objects.create(**common)


def test_progress_transitions_are_recorded_once(demo_map) -> None:
    vehicle = VehicleFactory()
    order = TransportOrder.objects.create(
        source=station(demo_map, "PICK-1"),
        destination=station(demo_map, "DROP-1"),
        vehicle=vehicle,
        status=TransportOrder.Status.ASSIGNED,
    )

    services.mark_order_started(order_id=order.pk)
    services.mark_order_started(order_id=order.pk)  # a repeated flush changes nothing
    services.mark_order_finished(order_id=order.pk)
    services.mark_order_failed(order_id=order.pk, reason="late failure")

    order.refresh_from_db()
    assert order.status == TransportOrder.Status.FINISHED
    assert order.started_at
    assert order.finished_at
    assert not order.failure_reason
    assert list(order.events.values_list("kind", flat=True)) == ["STARTED", "FINISHED"]


def test_cancel_of_a_new_order_is_immediate(demo_map) -> None:
    order = services.create_transport_order(
        source=station(demo_map, "PICK-1"), destination=station(demo_map, "DROP-1")
    )

    services.cancel_transport_order(order=order, reason="not needed")

    order.refresh_from_db()
    assert order.status == TransportOrder.Status.CANCELLED
    with pytest.raises(DomainError):
        services.cancel_transport_order(order=order)


def test_cancel_of_an_assigned_order_asks_control(
    demo_map, django_capture_on_commit_callbacks, sent_commands
) -> None:
    order = TransportOrder.objects.create(
        source=station(demo_map, "PICK-1"),
        destination=station(demo_map, "DROP-1"),
        vehicle=VehicleFactory(),
        status=TransportOrder.Status.ASSIGNED,
    )

    with django_capture_on_commit_callbacks(execute=True):
        services.cancel_transport_order(order=order, reason="wrong pallet")

    order.refresh_from_db()
    assert order.status == TransportOrder.Status.ASSIGNED
    assert order.cancel_requested
    assert sent_commands == [("order.cancel", {"order": order.pk})]


def test_requeue_returns_an_assigned_order_to_dispatch(demo_map) -> None:
    order = TransportOrder.objects.create(
        source=station(demo_map, "PICK-1"),
        destination=station(demo_map, "DROP-1"),
        vehicle=VehicleFactory(),
        route=["A0.0"],
        status=TransportOrder.Status.ASSIGNED,
    )

    services.requeue_order(order_id=order.pk, reason="vehicle moved")

    order.refresh_from_db()
    assert (order.status, order.vehicle, order.route) == ("NEW", None, [])
    assert order.events.get().kind == OrderEvent.Kind.REQUEUED
