"""Recurring transport orders: which slot is due, and creating each slot's order exactly once.

Beat runs `create_due_recurring_orders` every 30 s. Two beats that overlap (a second beat
started by mistake, a slow run) are safe: the schedule row is locked while its slot is
created, and the run table's unique (schedule, slot) refuses a second order for the same slot.
"""

import logging
from datetime import datetime, timedelta

from django.db import transaction
from django.utils import timezone

from fleet.exceptions import InvalidRequestError
from orders.models import RecurringOrder, RecurringOrderRun, TransportOrder
from orders.services.steps import check_steps, parse_steps
from orders.services.transport import create_transport_order

logger = logging.getLogger(__name__)


def due_slot(schedule: RecurringOrder, now: datetime) -> datetime | None:
    """The latest slot of `schedule` at or before `now` today (local time), or None when today
    is not one of its weekdays, the window has not opened or has closed, or the slot is older
    than the schedule itself."""
    local = timezone.localtime(now)
    if local.weekday() not in (schedule.weekdays or []):
        return None
    zone = local.tzinfo
    start = datetime.combine(local.date(), schedule.window_start, tzinfo=zone)
    end = datetime.combine(local.date(), schedule.window_end, tzinfo=zone)
    if local < start:
        return None
    interval = timedelta(minutes=schedule.interval_minutes)
    slot = start + ((local - start) // interval) * interval
    if slot >= end or slot < schedule.created_at.replace(second=0, microsecond=0):
        return None
    return slot


def create_due_recurring_orders(*, now: datetime | None = None) -> list[TransportOrder]:
    """Create the order of every active schedule's due slot that has none yet."""
    now = now or timezone.now()
    created = []
    for schedule in RecurringOrder.objects.filter(is_active=True).select_related("map"):
        slot = due_slot(schedule, now)
        if slot is None or (schedule.last_slot is not None and slot <= schedule.last_slot):
            continue
        order = _create_slot(schedule.pk, slot)
        if order is not None:
            created.append(order)
    return created


@transaction.atomic
def _create_slot(schedule_pk: int, slot: datetime) -> TransportOrder | None:
    schedule = (
        RecurringOrder.objects.select_for_update(of=("self",)).select_related("map", "vehicle_type")
    ).get(pk=schedule_pk)
    if schedule.last_slot is not None and slot <= schedule.last_slot:
        return None  # another beat got there first
    run, fresh = RecurringOrderRun.objects.get_or_create(schedule=schedule, slot=slot)
    if not fresh:
        return None
    order = None
    try:
        with transaction.atomic():
            order = create_transport_order(
                steps=parse_steps(schedule.map, schedule.steps),
                priority=schedule.priority,
                load_type=schedule.load_type,
                vehicle_type=schedule.vehicle_type,
                external_ref=f"recurring:{schedule.pk}:{slot:%Y%m%dT%H%M}",
                metadata={"recurring_order": schedule.pk, "slot": slot.isoformat()},
                created_by=schedule.created_by,
            )
    except InvalidRequestError as exc:
        # A station removed or made unreachable since: record it, never retry every 30 s.
        run.error = str(exc)[:300]
        logger.warning("recurring order %s slot %s: %s", schedule, slot, exc)
    run.order = order
    run.save(update_fields=["order", "error"])
    schedule.last_slot = slot
    schedule.save(update_fields=["last_slot"])
    return order


@transaction.atomic
def save_recurring_order(*, schedule: RecurringOrder) -> RecurringOrder:
    """Check a new or edited schedule (see `check_recurring_order`) and store it."""
    check_recurring_order(schedule)
    schedule.save()
    return schedule


def check_recurring_order(schedule: RecurringOrder) -> None:
    """Raise InvalidRequestError if the steps, window, interval or weekdays cannot work."""
    if not schedule.weekdays or not all(
        isinstance(d, int) and 0 <= d <= 6 for d in schedule.weekdays
    ):
        raise InvalidRequestError("weekdays must be a list of 0 (Monday) … 6 (Sunday)")
    if schedule.interval_minutes < 1:
        raise InvalidRequestError("the interval is at least one minute")
    if schedule.window_end <= schedule.window_start:
        raise InvalidRequestError("the window must end after it starts")
    check_steps(parse_steps(schedule.map, schedule.steps), vehicle_type=schedule.vehicle_type)
