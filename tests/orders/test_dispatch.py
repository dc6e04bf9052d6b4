"""Dispatch cycles and the reconciler against the database."""

from datetime import timedelta

import pytest
from django.utils import timezone

from orders import selectors, services
from orders.models import OrderEvent, TransportOrder
from tests.factories import VehicleFactory

Status = TransportOrder.Status


def new_order(station, pick: str = "PICK-1", drop: str = "DROP-1", **fields) -> TransportOrder:
    return TransportOrder.objects.create(source=station(pick), destination=station(drop), **fields)


def note(order: TransportOrder) -> str:
    order.refresh_from_db()
    return order.dispatch_note


def test_batch_assignment_gives_each_order_the_vehicle_that_makes_total_travel_least(
    station,
) -> None:
    # PICK-c hangs 2 m off A{c}.3; aisle nodes are 3 m apart. Greedy (oldest first) would give
    # PICK-2 the vehicle at A3.3 (5 m) and leave PICK-4 the one at A0.3 (14 m): 19 m in all.
    west = VehicleFactory(last_node_id="A0.3")
    east = VehicleFactory(last_node_id="A3.3")
    first = new_order(station, "PICK-2")
    second = new_order(station, "PICK-4")

    assigned = services.dispatch_pending_orders()

    first.refresh_from_db()
    second.refresh_from_db()
    assert {o.pk for o in assigned} == {first.pk, second.pk}
    assert (first.vehicle, second.vehicle) == (west, east)
    assert first.route[0] == "A0.3"
    assert first.route[-1] == "S-DROP-1"
    assert "S-PICK-2" in first.route
    assert first.vda_order_id == f"TO-{first.pk}"
    assert first.dispatch_note == ""


def test_orders_say_why_they_wait(station) -> None:
    order = new_order(station)

    services.dispatch_pending_orders()
    assert note(order) == "no vehicle online"

    VehicleFactory(paused=True)
    VehicleFactory(errors=[{"errorType": "x", "errorLevel": "FATAL"}])
    VehicleFactory(operating_mode="MANUAL")
    services.dispatch_pending_orders()
    assert note(order) == "no vehicle available: 1 in MANUAL mode, 1 in error, 1 paused"


def test_a_busy_fleet_and_an_unreachable_pickup_are_noted(station) -> None:
    busy = VehicleFactory()
    new_order(station, "PICK-2", vehicle=busy, status=Status.ASSIGNED)
    waiting = new_order(station)

    services.dispatch_pending_orders()
    assert note(waiting) == "no vehicle available: 1 busy"

    VehicleFactory(last_node_id="NOWHERE")
    services.dispatch_pending_orders()
    assert note(waiting) == "no vehicle can reach PICK-1"


def test_orders_wait_for_their_earliest_start(station) -> None:
    VehicleFactory()
    later = new_order(station, earliest_start=timezone.now() + timedelta(minutes=30))

    assert services.dispatch_pending_orders() == []
    assert note(later).startswith("waits for its earliest start")

    assigned = services.dispatch_pending_orders(now=timezone.now() + timedelta(hours=1))
    assert assigned == [later]


def test_priority_then_deadline_decide_who_gets_the_only_vehicle(station) -> None:
    VehicleFactory()
    plain = new_order(station, "PICK-1")
    due = new_order(station, "PICK-2", deadline=timezone.now() + timedelta(minutes=10))
    urgent = new_order(station, "PICK-3", priority=1)

    assert services.dispatch_pending_orders() == [urgent]
    assert "more urgent" in note(plain)
    assert "more urgent" in note(due)

    services.mark_order_finished(order_id=urgent.pk)
    assert services.dispatch_pending_orders() == [due]


def test_pending_orders_are_ranked_by_priority_then_deadline_missing_last_then_age(
    station, django_assert_num_queries
) -> None:
    now = timezone.now()
    oldest = new_order(station, "PICK-1")
    later_due = new_order(station, "PICK-2", deadline=now + timedelta(hours=2))
    urgent = new_order(station, "PICK-3", priority=2)
    sooner_due = new_order(station, "PICK-4", deadline=now + timedelta(hours=1))
    newest = new_order(station, "PICK-1")
    TransportOrder.objects.filter(pk=oldest.pk).update(created_at=now - timedelta(minutes=5))
    new_order(station, "PICK-2", status=Status.ASSIGNED)  # not pending

    # The orders and their steps; the intended vehicle and type reads run only when one is set.
    with django_assert_num_queries(2):
        pending = selectors.list_pending_orders()

    assert pending == [urgent, sooner_due, later_due, oldest, newest]


def test_a_cycle_reads_the_battery_facts_once_however_many_orders_it_assigns(
    station, django_assert_num_queries
) -> None:
    from django.db import connection
    from django.test.utils import CaptureQueriesContext

    def cycle_queries(orders: int) -> int:
        TransportOrder.objects.all().delete()
        VehicleFactory.create_batch(orders, battery_charge=90.0, last_node_id="A1.3")
        for _ in range(orders):
            new_order(station, "PICK-2")
        with CaptureQueriesContext(connection) as queries:
            assert len(services.dispatch_pending_orders()) == orders
        return len(queries.captured_queries)

    cycle_queries(1)  # builds the routing graph
    one, three = cycle_queries(1), cycle_queries(3)
    # Per further order only its claim: savepoint, UPDATE, the event's INSERT, release. The
    # policies, consumption and chargers are read once (they were three more queries an order).
    assert three - one == 2 * 4


def test_the_vehicle_idle_longest_gets_the_order_on_a_tie(station) -> None:
    recently_busy = VehicleFactory(last_node_id="A1.3")
    long_idle = VehicleFactory(last_node_id="A1.3")
    new_order(
        station,
        "PICK-2",
        vehicle=recently_busy,
        status=Status.FINISHED,
        finished_at=timezone.now() - timedelta(minutes=1),
    )
    new_order(
        station,
        "PICK-3",
        vehicle=long_idle,
        status=Status.FINISHED,
        finished_at=timezone.now() - timedelta(hours=2),
    )
    order = new_order(station, "PICK-1")

    services.dispatch_pending_orders()

    order.refresh_from_db()
    assert order.vehicle == long_idle


def test_a_vehicle_taken_meanwhile_is_refused_by_the_database(station) -> None:
    vehicle = VehicleFactory()
    order = new_order(station)
    # Another dispatch run gave the vehicle an order after this run read the idle vehicles.
    new_order(station, "PICK-2", vehicle=vehicle, status=Status.ASSIGNED)

    from orders.services import dispatch

    assert not dispatch._assign(order=order, vehicle=vehicle, route=["A0.0"], route_steps=[0])
    order.refresh_from_db()
    assert order.status == Status.NEW


def test_dispatch_of_a_cancelled_or_assigned_order_does_nothing(station) -> None:
    vehicle = VehicleFactory()
    order = new_order(station, cancel_requested=True)

    assert services.dispatch_pending_orders() == []
    from orders.services import dispatch

    assert not dispatch._assign(order=order, vehicle=vehicle, route=["A0.0"], route_steps=[0])


def stale(station, vehicle, *, minutes: float = 5, **fields) -> TransportOrder:
    assigned_at = timezone.now() - timedelta(minutes=minutes)
    order = new_order(station, vehicle=vehicle, status=Status.ASSIGNED, route=["A0.0"], **fields)
    TransportOrder.objects.filter(pk=order.pk).update(
        assigned_at=assigned_at, vda_order_id=f"TO-{order.pk}"
    )
    return order


def test_reconciler_requeues_an_assignment_the_vehicle_never_got(station) -> None:
    vehicle = VehicleFactory(last_seen=timezone.now(), order_id="TO-old")
    order = stale(station, vehicle)

    assert services.reconcile_stale_assignments() == [order.pk]

    order.refresh_from_db()
    assert (order.status, order.vehicle, order.route) == (Status.NEW, None, [])
    event = order.events.get(kind=OrderEvent.Kind.REQUEUED)
    assert event.detail["by"] == "reconciler"
    assert "not started within 120 s" in event.detail["reason"]


@pytest.mark.parametrize(
    ("vehicle_fields", "order_fields", "minutes"),
    [
        ({"last_seen": "now"}, {}, 1),  # within the lease
        ({"last_seen": "now"}, {"sent_at": "now"}, 5),  # control sent it
        ({"last_seen": "now", "order_id": "same"}, {}, 5),  # the vehicle reports it
        ({"last_seen": "assigned"}, {}, 5),  # silent since the assignment: may have it
        ({"last_seen": None}, {}, 5),
        ({"last_seen": "now"}, {"cancel_requested": True}, 5),
    ],
)
def test_reconciler_leaves_alone_what_control_may_have_sent(
    station, vehicle_fields, order_fields, minutes
) -> None:
    now = timezone.now()
    vehicle = VehicleFactory()
    order = stale(station, vehicle, minutes=minutes)
    moments = {"now": now, "assigned": now - timedelta(minutes=minutes), None: None}
    vehicle.last_seen = moments[vehicle_fields["last_seen"]]
    if vehicle_fields.get("order_id") == "same":
        vehicle.order_id = f"TO-{order.pk}"
    vehicle.save()
    TransportOrder.objects.filter(pk=order.pk).update(
        **{k: (now if v == "now" else v) for k, v in order_fields.items()}
    )

    assert services.reconcile_stale_assignments() == []
    order.refresh_from_db()
    assert order.status == Status.ASSIGNED


def test_the_lease_is_configurable(station, settings) -> None:
    settings.FLEET_ORDERS = {"ASSIGNMENT_LEASE": 30.0}
    vehicle = VehicleFactory(last_seen=timezone.now())
    order = stale(station, vehicle, minutes=1)

    assert services.reconcile_stale_assignments() == [order.pk]


def test_mark_order_sent_is_recorded_once(station) -> None:
    order = stale(station, VehicleFactory())

    services.mark_order_sent(order_id=order.pk)
    first = TransportOrder.objects.get(pk=order.pk).sent_at
    services.mark_order_sent(order_id=order.pk)

    assert first is not None
    assert TransportOrder.objects.get(pk=order.pk).sent_at == first


def test_dispatch_task_and_reconcile_task_run_the_services(station) -> None:
    from orders.tasks import dispatch_pending_orders_task, reconcile_assignments_task

    VehicleFactory()
    new_order(station)

    assert dispatch_pending_orders_task.delay().get() == 1
    assert reconcile_assignments_task.delay().get() == 0


def test_a_cycle_wakes_control_once_for_all_its_assignments(
    station, sent_commands, django_capture_on_commit_callbacks
) -> None:
    VehicleFactory(last_node_id="A0.3")
    VehicleFactory(last_node_id="A3.3")
    orders = [new_order(station, "PICK-2"), new_order(station, "PICK-4")]

    with django_capture_on_commit_callbacks(execute=True):
        services.dispatch_pending_orders()
        assert sent_commands == []  # not before the assignments commit

    assert [kind for kind, _ in sent_commands] == ["order.assigned"]
    assert sorted(sent_commands[0][1]["orders"]) == sorted(o.pk for o in orders)


def test_a_cycle_without_assignments_does_not_wake_control(
    station, sent_commands, django_capture_on_commit_callbacks
) -> None:
    new_order(station)

    with django_capture_on_commit_callbacks(execute=True):
        services.dispatch_pending_orders()

    assert sent_commands == []


def test_orders_on_a_map_without_idle_vehicles_say_so(station) -> None:
    VehicleFactory(map_id="hall-2", last_node_id="X")
    order = new_order(station)

    services.dispatch_pending_orders()

    assert note(order) == "no idle vehicle on map demo"


def test_a_broker_outage_never_fails_the_write_that_triggers_dispatch(
    station, monkeypatch, django_capture_on_commit_callbacks
) -> None:
    from orders.tasks import dispatch_pending_orders_task

    def broker_down() -> None:
        raise ConnectionError("broker down")

    monkeypatch.setattr(dispatch_pending_orders_task, "delay", broker_down)

    with django_capture_on_commit_callbacks(execute=True):
        order = services.create_transport_order(
            source=station("PICK-1"), destination=station("DROP-1")
        )

    assert TransportOrder.objects.get(pk=order.pk).status == Status.NEW


def test_the_periodic_jobs_register_with_beat() -> None:
    from fleet.celery import app
    from orders.tasks import schedule_periodic_tasks

    schedule_periodic_tasks(sender=app)

    schedule = app.conf.beat_schedule
    assert schedule["orders-reconcile-assignments"]["task"] == "orders.tasks.reconcile_assignments"
    assert schedule["orders-deliver-due-webhooks"]["task"] == "orders.tasks.deliver_due_webhooks"
    assert schedule["orders-prune"]["task"] == "orders.tasks.prune"


def test_a_vehicle_told_to_pause_charge_or_park_is_left_alone_for_a_while(station) -> None:
    parked, paused, resumed = VehicleFactory(), VehicleFactory(), VehicleFactory()
    services.send_vehicle_to_park(vehicle=parked)
    services.pause_vehicle(vehicle=paused)
    services.pause_vehicle(vehicle=resumed)
    services.resume_vehicle(vehicle=resumed)
    order = new_order(station)

    services.dispatch_pending_orders()

    order.refresh_from_db()
    assert order.vehicle == resumed
    later = timezone.now() + timedelta(minutes=3)
    other = new_order(station, "PICK-2")
    assert services.dispatch_pending_orders(now=later) == [other]
