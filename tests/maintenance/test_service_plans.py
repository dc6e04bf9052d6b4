"""Acceptance (issue 7): a service plan fires a work order when a counter crosses its interval,
the vehicle gets no orders until the work order is done, and the history shows it."""

from datetime import timedelta
from typing import Any

import pytest
from django.utils import timezone

from fleet.exceptions import DomainError, InvalidRequestError
from maintenance import selectors, services
from maintenance.models import ServiceEvent, ServicePlan, VehicleCounters, WorkOrder
from maintenance.services.observe import CounterObserver
from orders.models import TransportOrder
from orders.services import dispatch_pending_orders
from tests.factories import VehicleFactory

Kind = ServiceEvent.Kind
pytestmark = pytest.mark.django_db


def drive(observer: CounterObserver, vehicle: Any, metres: int, start: float = 0.0) -> float:
    """One snapshot a second at 1 m/s along x from x = start, online in AUTOMATIC mode."""
    now = start
    for step in range(metres + 1):
        now = start + step
        observer.observe(
            [
                {
                    "pk": vehicle.pk,
                    "x": now,
                    "y": 0.0,
                    "map_id": "demo",
                    "driving": True,
                    "connection": "ONLINE",
                    "operating_mode": "AUTOMATIC",
                    "battery_charge": 80.0,
                    "charging": False,
                    "errors": [],
                }
            ],
            now=now,
        )
    observer.write([vehicle.pk], now)
    return now


def test_a_distance_plan_takes_the_vehicle_out_of_service_until_the_work_is_done(
    station: Any,
) -> None:
    vehicle = VehicleFactory()
    plan = ServicePlan.objects.create(name="Wheel check", interval_km=0.5)
    observer = CounterObserver()
    assert services.check_service_plans() == []  # applied now: the baseline is 0 km

    drive(observer, vehicle, 400)
    assert services.check_service_plans() == []  # 0.4 km < 0.5 km
    drive(observer, vehicle, 150, start=1000.0)
    (work_order,) = services.check_service_plans()

    counters = VehicleCounters.objects.get(vehicle=vehicle)
    assert counters.distance_m == pytest.approx(550.0)  # the jump 400 → 1000 m is not driven
    assert counters.driving_seconds == pytest.approx(550.0)
    assert (work_order.status, work_order.plan) == (WorkOrder.Status.DUE, plan)
    assert "distance: 0.6km" in work_order.trigger
    assert services.check_service_plans() == []  # fires once until done

    order = TransportOrder.objects.create(source=station("PICK-1"), destination=station("DROP-1"))
    assert dispatch_pending_orders() == []
    order.refresh_from_db()
    assert order.dispatch_note == "no vehicle available: 1 in maintenance"

    services.advance_work_order(work_order=work_order, status="IN_PROGRESS", notes="tyres worn")
    assert dispatch_pending_orders() == []
    services.advance_work_order(
        work_order=work_order, status="DONE", parts=[{"part": "tyre 200x50", "qty": 2}]
    )
    assert dispatch_pending_orders() == [order]

    work_order.refresh_from_db()
    assert work_order.parts == [{"part": "tyre 200x50", "qty": 2}]
    assert "tyres worn" in work_order.notes
    history = [e.kind for e in selectors.service_history(vehicle=vehicle)][::-1]
    assert history == [
        Kind.WORK_ORDER_DUE,
        Kind.OUT_OF_SERVICE,
        Kind.WORK_ORDER_STARTED,
        Kind.WORK_ORDER_DONE,
        Kind.BACK_IN_SERVICE,
    ]
    # Done resets the interval: the next work order needs another 0.5 km.
    drive(observer, vehicle, 100, start=5000.0)
    assert services.check_service_plans() == []


def test_hours_cycles_and_calendar_days_fire_too() -> None:
    vehicle = VehicleFactory()
    by_days = ServicePlan.objects.create(
        name="Monthly", interval_days=30, takes_out_of_service=False
    )
    by_cycles = ServicePlan.objects.create(name="Battery", interval_cycles=1.0)
    services.check_service_plans()
    VehicleCounters.objects.filter(vehicle=vehicle).update(charge_cycles=1.2)

    fired = services.check_service_plans(now=timezone.now() + timedelta(days=31))

    assert {w.plan for w in fired} == {by_days, by_cycles}
    reasons = selectors.out_of_service(vehicle_ids=[vehicle.pk])
    assert reasons == {
        vehicle.pk: "in maintenance (work order "
        f"{next(w.pk for w in fired if w.plan == by_cycles)}: Battery)"
    }


def test_an_overdue_work_order_is_noted_once() -> None:
    vehicle = VehicleFactory()
    ServicePlan.objects.create(name="Daily", interval_days=1, grace_days=1)
    services.check_service_plans()
    later = timezone.now() + timedelta(days=1, minutes=1)
    (work_order,) = services.check_service_plans(now=later)
    services.check_service_plans(now=later + timedelta(days=2))
    services.check_service_plans(now=later + timedelta(days=3))
    assert ServiceEvent.objects.filter(kind=Kind.OVERDUE, work_order=work_order).count() == 1
    assert list(selectors.list_overdue_work_orders()) == [work_order]
    assert vehicle.pk in selectors.out_of_service(vehicle_ids=[vehicle.pk])


def test_plans_apply_to_their_vehicle_or_type_only() -> None:
    mine, other = VehicleFactory(), VehicleFactory()
    ServicePlan.objects.create(name="Only mine", vehicle=mine, interval_days=1)
    services.check_service_plans()
    fired = services.check_service_plans(now=timezone.now() + timedelta(days=2))
    assert [w.vehicle for w in fired] == [mine]
    assert other.pk not in selectors.out_of_service(vehicle_ids=[other.pk])


def test_out_of_service_and_back_by_staff(station: Any) -> None:
    vehicle = VehicleFactory()
    with pytest.raises(InvalidRequestError):
        services.take_out_of_service(vehicle=vehicle, reason=" ")
    services.take_out_of_service(vehicle=vehicle, reason="bumper cracked")
    with pytest.raises(DomainError):
        services.take_out_of_service(vehicle=vehicle, reason="again")
    order = TransportOrder.objects.create(source=station("PICK-1"), destination=station("DROP-1"))
    assert dispatch_pending_orders() == []
    order.refresh_from_db()
    assert order.dispatch_note == "no vehicle available: 1 out of service"

    services.return_to_service(vehicle=vehicle)
    assert dispatch_pending_orders() == [order]
    kinds = [e.kind for e in selectors.service_history(vehicle=vehicle)][::-1]
    assert kinds == [Kind.OUT_OF_SERVICE, Kind.BACK_IN_SERVICE]


def test_work_orders_move_forward_only() -> None:
    work_order = services.create_work_order(vehicle=VehicleFactory(), title="Squeaks")
    with pytest.raises(InvalidRequestError):
        services.advance_work_order(work_order=work_order, status="LATER")
    services.advance_work_order(work_order=work_order, status="DONE")
    with pytest.raises(DomainError):
        services.advance_work_order(work_order=work_order, status="IN_PROGRESS")
    with pytest.raises(InvalidRequestError):
        services.create_work_order(vehicle=work_order.vehicle, title="")
