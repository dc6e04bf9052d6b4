"""Celery tasks that keep the report tables current (scheduled by beat, see settings)."""

from celery import shared_task

from reports import services


@shared_task(name="reports.tasks.roll_up_orders", ignore_result=True)
def roll_up_orders_task() -> int:
    return services.roll_up_orders()


@shared_task(name="reports.tasks.sample_vehicles", ignore_result=True)
def sample_vehicles_task() -> int:
    return services.sample_vehicles()


@shared_task(name="reports.tasks.roll_up_traffic_waits", ignore_result=True)
def roll_up_traffic_waits_task() -> int:
    from reports import waits

    return waits.roll_up_traffic_waits()
