"""Celery tasks of the alerts app (thin: the work is in services)."""

from celery import shared_task

from alerts import services


@shared_task(name="alerts.escalate")
def escalate_alerts_task() -> int:
    """Beat runs this every minute: notify about alerts unacknowledged past their rule."""
    return services.escalate_alerts()
