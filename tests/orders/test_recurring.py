"""Recurring orders: slots on weekdays in a window, one order per slot even with two beats."""

import threading
from datetime import UTC, datetime, time

import pytest
from django.db import connection

from fleet.exceptions import InvalidRequestError
from maps.models import Map
from orders import services
from orders.models import RecurringOrder, RecurringOrderRun, TransportOrder
from orders.services.recurring import due_slot

STEPS = [{"station": "PICK-1", "operation": "PICK"}, {"station": "DROP-2", "operation": "DROP"}]
MONDAY = datetime(2030, 1, 7, tzinfo=UTC)  # TIME_ZONE is UTC in the tests


def at(day: datetime, hour: int, minute: int, second: int = 0) -> datetime:
    return day.replace(hour=hour, minute=minute, second=second)


def schedule(demo_map: Map, **fields) -> RecurringOrder:  # type: ignore[no-untyped-def]
    fields.setdefault("name", "A to B")
    recurring = services.save_recurring_order(
        schedule=RecurringOrder(
            map=demo_map,
            steps=STEPS,
            interval_minutes=15,
            window_start=time(6),
            window_end=time(22),
            **fields,
        )
    )
    # As if set up long ago, so no slot is older than the schedule.
    RecurringOrder.objects.filter(pk=recurring.pk).update(
        created_at=datetime(2020, 1, 1, tzinfo=UTC)
    )
    recurring.refresh_from_db()
    return recurring


def test_slots_every_15_minutes_on_weekdays_inside_the_window(demo_map) -> None:
    recurring = schedule(demo_map)

    assert due_slot(recurring, at(MONDAY, 6, 0)) == at(MONDAY, 6, 0)
    assert due_slot(recurring, at(MONDAY, 10, 29, 59)) == at(MONDAY, 10, 15)
    assert due_slot(recurring, at(MONDAY, 21, 59)) == at(MONDAY, 21, 45)
    assert due_slot(recurring, at(MONDAY, 5, 59)) is None
    assert due_slot(recurring, at(MONDAY, 22, 0)) is None
    saturday = MONDAY.replace(day=12)
    assert due_slot(recurring, at(saturday, 10, 0)) is None


def test_each_due_slot_creates_one_order_and_only_the_latest_slot_counts(demo_map) -> None:
    recurring = schedule(demo_map)

    first = services.create_due_recurring_orders(now=at(MONDAY, 10, 1))
    again = services.create_due_recurring_orders(now=at(MONDAY, 10, 14))
    # The beat was down for an hour: only the latest slot gets an order, not four.
    later = services.create_due_recurring_orders(now=at(MONDAY, 11, 20))

    assert (len(first), again, len(later)) == (1, [], 1)
    (order,) = first
    assert [(s.station.station_id, s.operation) for s in order.steps.all()] == [
        ("PICK-1", "PICK"),
        ("DROP-2", "DROP"),
    ]
    assert order.external_ref == f"recurring:{recurring.pk}:20300107T1000"
    assert list(RecurringOrderRun.objects.values_list("slot", flat=True)) == [
        at(MONDAY, 11, 15),
        at(MONDAY, 10, 0),
    ]


def test_inactive_schedules_and_slots_older_than_the_schedule_create_nothing(demo_map) -> None:
    schedule(demo_map, is_active=False)
    fresh = schedule(demo_map, name="fresh")
    RecurringOrder.objects.filter(pk=fresh.pk).update(created_at=at(MONDAY, 10, 7, 30))

    before = services.create_due_recurring_orders(now=at(MONDAY, 10, 10))
    after = services.create_due_recurring_orders(now=at(MONDAY, 10, 16))

    assert before == []
    assert [o.metadata["recurring_order"] for o in after] == [fresh.pk]


@pytest.mark.parametrize(
    ("fields", "reason"),
    [
        ({"steps": [{"station": "NOPE", "operation": "PICK"}]}, "no station 'NOPE'"),
        ({"steps": []}, "non-empty list"),
        ({"weekdays": [7]}, "weekdays"),
        ({"window_start": time(22), "window_end": time(6)}, "window must end"),
    ],
)
def test_a_bad_schedule_is_refused_with_the_reason(demo_map, fields, reason) -> None:
    values = {
        "name": "bad",
        "map": demo_map,
        "steps": STEPS,
        "window_start": time(6),
        "window_end": time(22),
        **fields,
    }
    with pytest.raises(InvalidRequestError, match=reason):
        services.save_recurring_order(schedule=RecurringOrder(**values))
    assert not RecurringOrder.objects.exists()


@pytest.mark.django_db(transaction=True)
def test_two_overlapping_beats_create_the_slot_once(demo_map) -> None:
    schedule(demo_map)
    barrier = threading.Barrier(4)
    results: list[int] = []

    def beat() -> None:
        try:
            barrier.wait()
            results.append(len(services.create_due_recurring_orders(now=at(MONDAY, 9, 3))))
        finally:
            connection.close()

    threads = [threading.Thread(target=beat) for _ in range(4)]
    for thread in threads:
        thread.start()
    for thread in threads:
        thread.join()

    assert sorted(results) == [0, 0, 0, 1]
    assert TransportOrder.objects.count() == 1
    assert RecurringOrderRun.objects.get().order == TransportOrder.objects.get()


def test_a_slot_whose_steps_broke_is_recorded_not_retried(demo_map) -> None:
    recurring = schedule(demo_map)
    RecurringOrder.objects.filter(pk=recurring.pk).update(
        steps=[{"station": "GONE", "operation": "PICK"}]
    )

    assert services.create_due_recurring_orders(now=at(MONDAY, 9, 3)) == []
    assert services.create_due_recurring_orders(now=at(MONDAY, 9, 4)) == []

    run = RecurringOrderRun.objects.get()
    assert (run.order, run.error) == (None, "step 1: no station 'GONE' on map demo")
