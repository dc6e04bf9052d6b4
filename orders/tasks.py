"""Celery tasks of the orders app: thin wrappers around services."""

from celery import shared_task


@shared_task(name="orders.tasks.dispatch_pending_orders", ignore_result=True)
def dispatch_pending_orders_task() -> int:
    """Run one dispatch cycle; triggered by new orders, finished orders and the beat schedule."""
    from orders import services

    return len(services.dispatch_pending_orders())
