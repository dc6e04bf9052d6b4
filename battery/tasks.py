"""Celery tasks of the battery app (thin wrappers; schedule in settings CELERY_BEAT_SCHEDULE)."""

from celery import shared_task


@shared_task(name="battery.tasks.plan_charging", ignore_result=True)
def plan_charging_task() -> int:
    """One charging cycle: stop, open, queue and assign charging sessions."""
    from battery import services

    cycle = services.plan_charging()
    return len(cycle.assigned)
