"""The lost-vehicle policy: wait, reassign or fail the orders of a vehicle that is gone."""

from datetime import timedelta

import pytest
from django.utils import timezone

from orders import services
from orders.models import OrderEvent, TransportOrder
from tests.factories import VehicleFactory

Status = TransportOrder.Status
T0 = timezone.now()
GRACE = timedelta(seconds=120)


def active_order(station, vehicle, *, sent: bool) -> TransportOrder:
    return TransportOrder.objects.create(
        source=station("PICK-1"),
        destination=station("DROP-1"),
        vehicle=vehicle,
        status=Status.IN_PROGRESS if sent else Status.ASSIGNED,
        assigned_at=T0,
        sent_at=T0 if sent else None,
        vda_order_id="TO-x",
    )


def timeline(order: TransportOrder) -> list[tuple[str, dict]]:
    return list(order.events.order_by("pk").values_list("kind", "detail"))


@pytest.fixture
def policy(settings):
    def choose(name: str) -> None:
        settings.FLEET_ORDERS = {"LOST_VEHICLE_POLICY": name, "LOST_VEHICLE_GRACE": 120.0}

    return choose


def test_by_default_orders_wait_for_their_vehicle_and_the_timeline_says_so(station, policy) -> None:
    policy("wait")
    vehicle = VehicleFactory(connection="OFFLINE")
    order = active_order(station, vehicle, sent=True)

    assert services.handle_lost_vehicles(now=T0) == []
    assert services.handle_lost_vehicles(now=T0 + GRACE * 10) == []
    order.refresh_from_db()
    assert order.status == Status.IN_PROGRESS
    assert timeline(order) == [
        (OrderEvent.Kind.UPDATED, {"vehicle_lost": f"{vehicle} is offline", "policy": "wait"})
    ]
    vehicle.connection = "ONLINE"
    vehicle.save()
    services.handle_lost_vehicles(now=T0 + GRACE * 11)
    order.refresh_from_db()
    assert order.vehicle_lost_at is None
    assert timeline(order)[-1] == (OrderEvent.Kind.UPDATED, {"vehicle_back": str(vehicle)})


def test_reassign_moves_only_orders_the_vehicle_never_received(station, policy) -> None:
    policy("reassign")
    vehicle = VehicleFactory(errors=[{"errorType": "drive", "errorLevel": "FATAL"}])
    unsent = active_order(station, vehicle, sent=False)
    sent = active_order(station, VehicleFactory(operating_mode="MANUAL"), sent=True)

    services.handle_lost_vehicles(now=T0)
    assert services.handle_lost_vehicles(now=T0 + GRACE / 2) == []  # within the grace time
    assert services.handle_lost_vehicles(now=T0 + GRACE) == [unsent.pk]
    unsent.refresh_from_db()
    sent.refresh_from_db()
    assert (unsent.status, unsent.vehicle) == (Status.NEW, None)
    assert "has a FATAL error for 120 s (lost-vehicle policy reassign)" in unsent.dispatch_note
    assert sent.status == Status.IN_PROGRESS  # it may already carry the load: it waits


def test_fail_fails_unsent_orders_and_cancels_the_others_once(station, policy) -> None:
    policy("fail")
    unsent = active_order(station, VehicleFactory(connection="CONNECTIONBROKEN"), sent=False)
    sent = active_order(station, VehicleFactory(connection="CONNECTIONBROKEN"), sent=True)

    services.handle_lost_vehicles(now=T0)
    assert sorted(services.handle_lost_vehicles(now=T0 + GRACE)) == sorted([unsent.pk, sent.pk])
    assert services.handle_lost_vehicles(now=T0 + GRACE * 2) == []  # the cancel is asked once
    unsent.refresh_from_db()
    sent.refresh_from_db()
    assert unsent.status == Status.FAILED
    assert "connection broken for 120 s" in unsent.failure_reason
    assert (sent.status, sent.cancel_requested) == (Status.IN_PROGRESS, True)
    assert "lost-vehicle policy fail" in timeline(sent)[-1][1]["reason"]


def test_an_unknown_policy_is_refused(settings) -> None:
    settings.FLEET_ORDERS = {"LOST_VEHICLE_POLICY": "pray"}
    with pytest.raises(ValueError, match="LOST_VEHICLE_POLICY must be one of"):
        services.handle_lost_vehicles()
