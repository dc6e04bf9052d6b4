"""Dispatch's decoded factsheets: fetched once per change, never stale."""

import pytest

from orders import services
from orders.models import TransportOrder
from orders.services.dispatch_factsheets import attach_factsheets, factsheet_digest, forget
from robots.models import Vehicle
from tests.factories import VehicleFactory

CRITICAL_50 = {"vehicleConfig": {"batteryCharging": {"criticalLowChargingLevel": 50.0}}}
CRITICAL_30 = {"vehicleConfig": {"batteryCharging": {"criticalLowChargingLevel": 30.0}}}


@pytest.fixture(autouse=True)
def fresh_cache() -> None:
    forget()


def deferred(*vehicles: Vehicle) -> list[Vehicle]:
    """The vehicles as dispatch loads them: without the factsheet."""
    return list(Vehicle.objects.filter(pk__in=[v.pk for v in vehicles]).defer("factsheet"))


@pytest.mark.django_db
def test_an_unchanged_factsheet_is_not_fetched_again(django_assert_num_queries) -> None:
    vehicle = VehicleFactory(factsheet=CRITICAL_50)
    attach_factsheets(deferred(vehicle))

    again = deferred(vehicle)
    with django_assert_num_queries(1):  # the fingerprints only
        attach_factsheets(again)

    assert again[0].factsheet == CRITICAL_50


@pytest.mark.django_db
def test_fingerprints_read_with_the_vehicles_save_the_query(django_assert_num_queries) -> None:
    vehicle = VehicleFactory(factsheet=CRITICAL_50)
    attach_factsheets(deferred(vehicle))
    Vehicle.objects.filter(pk=vehicle.pk).update(factsheet=CRITICAL_30)

    rows = list(
        Vehicle.objects.filter(pk=vehicle.pk)
        .defer("factsheet")
        .annotate(factsheet_digest=factsheet_digest())
    )
    with django_assert_num_queries(1):  # only the changed factsheet
        attach_factsheets(rows, {v.pk: v.factsheet_digest for v in rows})
    assert rows[0].factsheet == CRITICAL_30

    with django_assert_num_queries(0):
        attach_factsheets(rows, {v.pk: v.factsheet_digest for v in rows})


@pytest.mark.django_db
def test_a_changed_or_removed_factsheet_is_fetched(django_assert_num_queries) -> None:
    changed, removed, never = (
        VehicleFactory(factsheet=CRITICAL_50),
        VehicleFactory(factsheet=CRITICAL_50),
        VehicleFactory(factsheet=None),
    )
    attach_factsheets(deferred(changed, removed, never))
    Vehicle.objects.filter(pk=changed.pk).update(factsheet=CRITICAL_30)
    Vehicle.objects.filter(pk=removed.pk).update(factsheet=None)

    vehicles = deferred(changed, removed, never)
    with django_assert_num_queries(2):  # fingerprints, then the two that changed
        attach_factsheets(vehicles)

    by_pk = {v.pk: v.factsheet for v in vehicles}
    assert by_pk == {changed.pk: CRITICAL_30, removed.pk: None, never.pk: None}


def test_dispatch_sees_a_new_factsheet_at_its_next_cycle(station) -> None:
    VehicleFactory(battery_charge=40.0, factsheet=CRITICAL_50)
    order = TransportOrder.objects.create(source=station("PICK-1"), destination=station("DROP-1"))

    assert services.dispatch_pending_orders() == []
    order.refresh_from_db()
    assert "below its critical charge level" in order.dispatch_note

    Vehicle.objects.update(factsheet=CRITICAL_30)  # the vehicle sent a new factsheet

    assert services.dispatch_pending_orders() == [order]


@pytest.mark.django_db
def test_vehicles_of_one_type_share_the_decoded_parts_of_their_factsheets() -> None:
    catalogue = {"agvActions": [{"actionType": "pick", "actionScopes": ["NODE"]}]}
    first, second = (
        VehicleFactory(factsheet={"serialNumber": serial, "protocolFeatures": catalogue})
        for serial in ("A", "B")
    )

    vehicles = deferred(first, second)
    attach_factsheets(vehicles)

    one, two = (v.factsheet for v in vehicles)
    assert (one["serialNumber"], two["serialNumber"]) == ("A", "B")
    assert one["protocolFeatures"] == catalogue
    assert one["protocolFeatures"] is two["protocolFeatures"]
