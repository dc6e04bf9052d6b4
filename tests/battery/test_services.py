"""Battery services against the database: history, learning, alerts, charging sessions."""

from typing import Any

import pytest
from django.db import IntegrityError, transaction

from battery import selectors, services
from battery.models import BatteryAlert, BatterySample, Charger, ChargeSession, VehicleEnergy
from battery.services.observe import EnergyObserver
from fleet.exceptions import DomainError
from orders.models import TransportOrder
from orders.services import dispatch_pending_orders
from tests.factories import VehicleFactory

Status = ChargeSession.Status


def snap(vehicle: Any, charge: float, *, x: float = 0.0, charging: bool = False) -> dict:
    return {
        "pk": vehicle.pk,
        "battery_charge": charge,
        "charging": charging,
        "x": x,
        "y": 0.0,
        "map_id": "demo",
    }


def test_history_is_sampled_on_a_percent_change_not_every_message(db: None) -> None:
    vehicle = VehicleFactory()
    observer = EnergyObserver()
    for second, charge in enumerate([80.0, 79.9, 79.6, 79.2, 78.9, 78.8]):
        observer.observe([snap(vehicle, charge)], now=float(second))

    charges = sorted(BatterySample.objects.values_list("charge", flat=True))
    assert charges == [78.9, 80.0]  # the first reading and the first 1 % step


def test_consumption_cycles_and_health_are_learned_from_snapshots(db: None) -> None:
    vehicle = VehicleFactory()
    observer = EnergyObserver()
    charge, x = 90.0, 0.0
    for second in range(0, 240):  # 1 m/s at 0.05 %/m
        x += 1.0
        charge -= 0.05
        observer.observe([snap(vehicle, charge, x=x)], now=float(second))
    for second in range(240, 300):  # charging 0.5 %/s: 30 % = 0.3 cycles
        charge += 0.5
        observer.observe([snap(vehicle, charge, x=x, charging=True)], now=float(second))

    energy = VehicleEnergy.objects.get(vehicle=vehicle)
    assert energy.drain_per_metre == pytest.approx(0.05, rel=0.1)
    assert energy.charge_cycles == pytest.approx(0.3, abs=0.02)
    assert energy.baseline_per_metre is not None
    assert energy.health == pytest.approx(100.0, abs=5)


def test_low_and_critical_alerts_open_and_resolve(db: None) -> None:
    vehicle = VehicleFactory()
    observer = EnergyObserver()
    observer.observe([snap(vehicle, 25.0)], now=0.0)
    assert set(BatteryAlert.objects.values_list("level", "resolved_at")) == {("LOW", None)}
    observer.observe([snap(vehicle, 10.0)], now=1.0)
    assert BatteryAlert.objects.filter(resolved_at__isnull=True).count() == 2
    observer.observe([snap(vehicle, 50.0, charging=True)], now=2.0)
    assert not BatteryAlert.objects.filter(resolved_at__isnull=True).exists()


def test_the_flush_hook_never_raises(db: None, monkeypatch: pytest.MonkeyPatch) -> None:
    def broken(*args: Any, **kwargs: Any) -> int:
        raise RuntimeError("boom")

    monkeypatch.setattr(services.OBSERVER, "observe", broken)
    assert services.observe_snapshots(snapshots=[{"pk": 1, "battery_charge": 5}]) == 0


def test_the_database_refuses_two_vehicles_on_one_charging_point(chargers: list[Charger]) -> None:
    first, second = VehicleFactory(), VehicleFactory()
    ChargeSession.objects.create(
        vehicle=first, charger=chargers[0], point=0, status=Status.CHARGING, reason="LOW"
    )
    with pytest.raises(IntegrityError), transaction.atomic():
        ChargeSession.objects.create(
            vehicle=second, charger=chargers[0], point=0, status=Status.ASSIGNED, reason="LOW"
        )
    # A finished session frees the point.
    ChargeSession.objects.update(status=Status.DONE)
    ChargeSession.objects.create(
        vehicle=second, charger=chargers[0], point=0, status=Status.ASSIGNED, reason="LOW"
    )


def test_low_vehicles_queue_and_get_the_nearest_free_points(
    chargers: list[Charger], sent_commands: list, django_capture_on_commit_callbacks: Any
) -> None:
    low = VehicleFactory(battery_charge=25.0, last_node_id="A5.0")
    critical = VehicleFactory(battery_charge=12.0, last_node_id="A0.0")
    third = VehicleFactory(battery_charge=28.0, last_node_id="A5.3")
    VehicleFactory(battery_charge=95.0)  # fine: stays

    with django_capture_on_commit_callbacks(execute=True):
        cycle = services.plan_charging(work_waiting=True)

    assert len(cycle.opened) == 3
    sessions = {s.vehicle_id: s for s in ChargeSession.objects.all()}
    assigned = {pk for pk, s in sessions.items() if s.status == Status.ASSIGNED}
    # Critical first; the next free point goes to the lowest of the others.
    assert assigned == {critical.pk, low.pk}
    assert sessions[third.pk].status == Status.QUEUED
    assert cycle.queue == {sessions[third.pk].pk: 1}
    assert sessions[critical.pk].route[0] == "A0.0"
    assert sessions[critical.pk].route[-1] in {"S-CHARGE-1", "S-CHARGE-2"}
    assert {s.route[-1] for pk, s in sessions.items() if pk in assigned} == {
        "S-CHARGE-1",
        "S-CHARGE-2",
    }
    assert ("order.assigned", {"charge_session": sessions[low.pk].pk}) in sent_commands
    # The jobs control drives, and dispatch keeps all three away from work.
    assert {j["vehicle"] for j in selectors.list_charge_jobs()} == {critical.pk, low.pk}
    holds = selectors.dispatch_holds(vehicles=[low, critical, third])
    assert holds == {
        low.pk: "driving to a charger",
        critical.pk: "driving to a charger",
        third.pk: "battery low",
    }


def test_charging_stops_when_work_waits_and_the_point_frees_when_the_vehicle_leaves(
    chargers: list[Charger], sent_commands: list
) -> None:
    vehicle = VehicleFactory(battery_charge=20.0, last_node_id="A5.1")
    services.plan_charging(work_waiting=True)
    session = ChargeSession.objects.get(vehicle=vehicle)
    assert services.apply_charge_progress(session_id=session.pk, kind="sent")
    assert services.apply_charge_progress(session_id=session.pk, kind="step")
    vehicle.last_node_id, vehicle.charging, vehicle.battery_charge = "S-CHARGE-1", True, 55.0
    vehicle.save()

    services.plan_charging(work_waiting=True)
    session.refresh_from_db()
    assert session.status == Status.CHARGING  # below sufficient: keeps charging

    vehicle.battery_charge = 61.0
    vehicle.save()
    cycle = services.plan_charging(work_waiting=True)
    session.refresh_from_db()
    assert cycle.stopped == [session.pk]
    assert session.status == Status.STOPPING
    assert (
        "vehicle.instant_action",
        {"vehicle": vehicle.pk, "action_type": "stopCharging", "parameters": {}},
    ) in sent_commands
    assert selectors.dispatch_holds(vehicles=[vehicle]) == {}  # may take work again
    assert selectors.booked_points() == {(session.charger_id, 0)}  # still standing there

    vehicle.charging, vehicle.last_node_id = False, "A5.1"
    vehicle.save()
    services.plan_charging(work_waiting=True)
    session.refresh_from_db()
    assert session.status == Status.DONE
    assert selectors.booked_points() == set()


def test_idle_vehicles_charge_opportunistically_only_without_work(
    chargers: list[Charger],
) -> None:
    vehicle = VehicleFactory(battery_charge=70.0)
    assert services.plan_charging(work_waiting=True).opened == []
    assert len(services.plan_charging(work_waiting=False).opened) == 1
    session = ChargeSession.objects.get()
    assert (session.vehicle, session.reason) == (vehicle, ChargeSession.Reason.OPPORTUNITY)


def test_a_queued_opportunity_session_yields_to_work(chargers: list[Charger], station) -> None:
    for number, charger in enumerate(chargers, start=1):
        ChargeSession.objects.create(
            vehicle=VehicleFactory(charging=True, last_node_id=f"S-CHARGE-{number}"),
            charger=charger,
            point=0,
            status="CHARGING",
            reason="LOW",
        )
    vehicle = VehicleFactory(battery_charge=70.0)
    services.plan_charging(work_waiting=False)
    queued = ChargeSession.objects.get(vehicle=vehicle)
    assert queued.status == Status.QUEUED
    assert selectors.dispatch_holds(vehicles=[vehicle]) == {}

    order = TransportOrder.objects.create(source=station("PICK-1"), destination=station("DROP-1"))
    assert dispatch_pending_orders() == [order]
    services.plan_charging(work_waiting=False)
    queued.refresh_from_db()
    assert queued.status == Status.CANCELLED


def test_dispatch_gives_no_work_to_a_low_vehicle_and_refuses_jobs_it_cannot_finish(
    chargers: list[Charger], station
) -> None:
    order = TransportOrder.objects.create(source=station("PICK-1"), destination=station("DROP-1"))
    VehicleFactory(battery_charge=25.0)
    dispatch_pending_orders()
    order.refresh_from_db()
    assert order.status == "NEW"
    assert "battery low" in order.dispatch_note

    thirsty = VehicleFactory(battery_charge=40.0, last_node_id="A0.0")
    VehicleEnergy.objects.create(vehicle=thirsty, drain_per_metre=1.0)  # 1 % per metre
    dispatch_pending_orders()
    order.refresh_from_db()
    assert order.status == "NEW"
    assert "would drop to" in order.dispatch_note

    VehicleEnergy.objects.filter(vehicle=thirsty).update(drain_per_metre=0.05)
    dispatch_pending_orders()
    order.refresh_from_db()
    assert (order.status, order.vehicle) == ("ASSIGNED", thirsty)


def test_staff_requests_become_sessions_once(chargers: list[Charger]) -> None:
    vehicle = VehicleFactory()
    session = services.request_charge(vehicle_id=vehicle.pk, station_id="CHARGE-2")
    assert (session.reason, session.wanted_station) == ("MANUAL", "CHARGE-2")
    with pytest.raises(DomainError, match="already has a charge session"):
        services.request_charge(vehicle_id=vehicle.pk)
    with pytest.raises(DomainError, match="no active charger"):
        services.request_charge(vehicle_id=VehicleFactory().pk, station_id="PICK-1")

    services.plan_charging(work_waiting=True)
    session.refresh_from_db()
    assert session.status == Status.ASSIGNED
    assert session.route[-1] == "S-CHARGE-2"


def test_observing_a_flush_without_a_due_sample_costs_no_query(
    db: None, django_assert_num_queries: Any
) -> None:
    vehicles = [VehicleFactory() for _ in range(20)]
    observer = EnergyObserver()
    observer.observe([snap(v, 80.0) for v in vehicles], now=0.0)  # first readings: sampled

    with django_assert_num_queries(0):
        for second in range(1, 60):  # 0.01 % a second: no 1 % step within a minute
            observer.observe([snap(v, 80.0 - second / 100) for v in vehicles], now=float(second))


def test_chargers_are_created_for_charge_stations_once(demo_map: Any) -> None:
    from django.core.management import call_command

    call_command("create_chargers")
    call_command("create_chargers")
    assert sorted(Charger.objects.values_list("station__station_id", flat=True)) == [
        "CHARGE-1",
        "CHARGE-2",
    ]
