"""Celery tasks of the maintenance app (thin wrappers; schedule in settings)."""

from celery import shared_task


@shared_task(name="maintenance.tasks.check_service_plans", ignore_result=True)
def check_service_plans_task() -> int:
    """Fire due work orders and note overdue ones."""
    from maintenance import services

    return len(services.check_service_plans())
