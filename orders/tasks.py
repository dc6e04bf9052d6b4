"""Celery tasks of the orders app: thin wrappers around services, and their beat schedule.

Dispatch's schedule is in settings (CELERY_BEAT_SCHEDULE); the other periodic jobs of this app
register themselves below when the Celery app is finalized (worker and beat both do that after
importing the task modules).
"""

from typing import Any

from celery import Celery, shared_task

from fleet.celery import app


@shared_task(name="orders.tasks.dispatch_pending_orders", ignore_result=True)
def dispatch_pending_orders_task() -> int:
    """Run one dispatch cycle; triggered by new orders, finished orders and the beat schedule."""
    from orders import services
    from orders.services import dispatch_queue

    dispatch_queue.start_cycle()  # first: a request from now on queues one more cycle
    return len(services.dispatch_pending_orders())


@shared_task(name="orders.tasks.reconcile_assignments", ignore_result=True)
def reconcile_assignments_task() -> int:
    """Requeue orders assigned longer than the lease that control never sent, and apply the
    lost-vehicle policy to the orders of vehicles that are gone."""
    from orders import services

    return len(services.reconcile_stale_assignments()) + len(services.handle_lost_vehicles())


# A hard cap well above one attempt (timeouts are per connect and per read), so an endpoint
# that drips its answer byte by byte cannot hold a worker for long.
@shared_task(name="orders.tasks.deliver_webhook", ignore_result=True, time_limit=120)
def deliver_webhook_task(delivery_id: int) -> bool:
    """One attempt of one webhook delivery. Retries are scheduled in the database (the delivery's
    next_attempt_at, exponential backoff) and sent by `deliver_due_webhooks_task`, so no
    countdown outlives the broker's visibility timeout and a lost message costs only a delay."""
    from orders import services

    return services.attempt_webhook_delivery(delivery_id=delivery_id)


@shared_task(name="orders.tasks.deliver_due_webhooks", ignore_result=True)
def deliver_due_webhooks_task() -> int:
    """Queue every webhook delivery that is due: retries and sends whose task was lost."""
    from orders import services

    return services.enqueue_due_webhook_deliveries()


@shared_task(name="orders.tasks.prune", ignore_result=True)
def prune_task() -> int:
    """Delete expired idempotency keys and old finished webhook deliveries."""
    from orders import services

    return services.prune_idempotency_keys() + services.prune_webhook_deliveries()


@shared_task(name="orders.tasks.create_recurring_orders", ignore_result=True)
def create_recurring_orders_task() -> int:
    """Create the orders of recurring schedules whose slot is due (once per slot)."""
    from orders import services

    return len(services.create_due_recurring_orders())


PERIODIC = {
    "orders-create-recurring": (30.0, "orders.tasks.create_recurring_orders"),
    "orders-reconcile-assignments": (30.0, "orders.tasks.reconcile_assignments"),
    "orders-deliver-due-webhooks": (10.0, "orders.tasks.deliver_due_webhooks"),
    "orders-prune": (3600.0, "orders.tasks.prune"),
}


@app.on_after_finalize.connect
def schedule_periodic_tasks(sender: Celery, **kwargs: Any) -> None:
    """Add this app's periodic jobs to beat's schedule."""
    for name, (seconds, task) in PERIODIC.items():
        sender.add_periodic_task(seconds, sender.signature(task), name=name)
