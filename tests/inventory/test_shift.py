"""Issue 8 acceptance: a simulated shift keeps the inventory consistent with the loads the
vehicles report (0 discrepancies when nothing is injected), and every injected load fault is
detected and becomes an alert."""

import pytest
from django.test import override_settings

from alerts.models import Alert, Source
from inventory.models import Discrepancy, LoadCarrier, StorageLocation
from inventory.services import define_location, move_load, register_load
from maps.models import Station
from orders.models import TransportOrder
from orders.services import dispatch_pending_orders
from orders.services.floor import move_load_to

pytestmark = pytest.mark.django_db(transaction=True)


def stock(n: int) -> list[LoadCarrier]:
    picks = Station.objects.filter(kind=Station.Kind.PICK).order_by("station_id")
    drops = Station.objects.filter(kind=Station.Kind.DROP).order_by("station_id")
    for station in [*picks, *drops]:
        define_location(station=station, capacity=2)
    loads = []
    for i in range(n):
        load = register_load(load_id=f"L{i}")
        move_load(load=load, location=StorageLocation.objects.get(station=picks[i % len(picks)]))
        loads.append(load)
    return loads


def run_moves(harness, loads: list[LoadCarrier]) -> list[TransportOrder]:
    drops = list(Station.objects.filter(kind=Station.Kind.DROP).order_by("station_id"))
    orders = [
        move_load_to(load_id=load.load_id, destination=drops[i % len(drops)])
        for i, load in enumerate(loads)
    ]

    def done() -> bool:
        dispatch_pending_orders()
        return all(
            not o.is_open for o in TransportOrder.objects.filter(pk__in=[o.pk for o in orders])
        )

    harness.run_until(done, limit=600, step=2)
    harness.step(2)
    return orders


@override_settings(INVENTORY_DISCREPANCY_GRACE_SECONDS=1)
def test_a_clean_shift_ends_with_every_load_where_the_vehicles_put_it(make_harness) -> None:
    harness = make_harness(count=2)
    loads = stock(4)
    orders = run_moves(harness, loads)

    assert {o.status for o in TransportOrder.objects.filter(pk__in=[o.pk for o in orders])} == {
        "FINISHED"
    }
    for order in TransportOrder.objects.filter(pk__in=[o.pk for o in orders]):
        load = LoadCarrier.objects.get(load_id=order.load_id)
        assert load.location.station_id == order.destination_id
        assert load.vehicle is None
        assert [m.reason for m in load.movements.order_by("at", "pk")][-2:] == ["PICK", "DROP"]
    assert Discrepancy.objects.count() == 0
    assert Alert.objects.filter(source=Source.INVENTORY).count() == 0


def run_until_closed(harness, orders: list[TransportOrder]) -> None:
    def closed() -> bool:
        dispatch_pending_orders()
        return not TransportOrder.objects.filter(
            pk__in=[o.pk for o in orders], status__in=TransportOrder.OPEN_STATUSES
        ).exists()

    harness.run_until(closed, limit=600, step=1)
    harness.step(1)
    harness.step(1)


def detected(kind: str) -> list[Discrepancy]:
    found = list(Discrepancy.objects.filter(kind=kind))
    for d in found:  # every discrepancy is an alert with the same cause
        assert Alert.objects.filter(cause=d.key, source=Source.INVENTORY).exists()
    return found


@override_settings(INVENTORY_DISCREPANCY_GRACE_SECONDS=1)
def test_every_injected_load_fault_is_detected_and_alerted(make_harness) -> None:
    harness = make_harness(count=2)
    stock(4)
    drops = list(Station.objects.filter(kind=Station.Kind.DROP).order_by("station_id"))

    # 1. A phantom load: AGV-2 reports a load nobody put there.
    harness.faults["AGV-2"].phantom = "GHOST-1"
    for _ in range(3):
        harness.step(1)
    (phantom,) = detected(Discrepancy.Kind.UNEXPECTED_LOAD)
    assert phantom.load_id == "GHOST-1"
    assert Alert.objects.get(cause=phantom.key).is_open
    harness.faults["AGV-2"].take_off(harness.vehicle("AGV-2"), "GHOST-1")
    harness.step(1)
    assert not Alert.objects.get(cause=phantom.key).is_open  # cleared with its cause

    # 2. A drop onto a full location.
    for i in range(2):
        move_load(
            load=register_load(load_id=f"F{i}"),
            location=StorageLocation.objects.get(station=drops[0]),
        )
    run_until_closed(harness, [move_load_to(load_id="L0", destination=drops[0])])
    (full,) = detected(Discrepancy.Kind.DROP_FULL)
    assert full.load_id == "L0"

    # 3. A pick that comes up empty (the drop then fails: nothing to drop).
    for faults in harness.faults.values():
        faults.empty_picks = 1
    run_until_closed(harness, [move_load_to(load_id="L1", destination=drops[1])])
    (empty,) = detected(Discrepancy.Kind.PICK_EMPTY)
    assert empty.load_id == "L1"
    for faults in harness.faults.values():
        faults.empty_picks = 0

    # 4. A load lost on the way.
    order = move_load_to(load_id="L2", destination=drops[1])
    harness.run_until(
        lambda: (
            (dispatch_pending_orders() or True)
            and LoadCarrier.objects.get(load_id="L2").vehicle_id is not None
        ),
        limit=300,
    )
    harness.step(2)  # the vehicle reports it for a while
    carrier = LoadCarrier.objects.get(load_id="L2")
    harness.faults[carrier.vehicle.serial_number].lose = True
    run_until_closed(harness, [order])
    (lost,) = detected(Discrepancy.Kind.MISSING_LOAD)
    assert lost.load_id == "L2"

    # Exactly the four injected faults, nothing else.
    assert Discrepancy.objects.count() == 4
