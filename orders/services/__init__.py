"""All writes of the orders app, re-exported from their modules:

- `transport`: create, reprioritise and cancel orders; progress reported by `control`
- `steps`: the stops of an order and their checks
- `recurring`: scheduled orders staff set up, created by beat once per slot
- `dispatch`: the assignment cycle and the reconciler of stale assignments
- `vehicles`: commands to vehicles, queued for `control`
- `webhooks`: subscriptions, deliveries and their attempts
- `clients`, `idempotency`: integration clients, API tokens, Idempotency-Key bookkeeping
"""

from orders.services.clients import (
    authenticate_api_token,
    checked_scopes,
    create_integration_client,
    issue_api_token,
    revoke_api_token,
)
from orders.services.dispatch import dispatch_pending_orders, reconcile_stale_assignments
from orders.services.idempotency import (
    IdempotencyKeyInFlight,
    IdempotencyKeyReused,
    StoredResponse,
    claim_idempotency_key,
    complete_idempotency_key,
    prune_idempotency_keys,
    release_idempotency_key,
)
from orders.services.lost import handle_lost_vehicles
from orders.services.recurring import (
    check_recurring_order,
    create_due_recurring_orders,
    save_recurring_order,
)
from orders.services.steps import StepSpec, parse_steps
from orders.services.transport import (
    cancel_transport_order,
    create_transport_order,
    mark_order_cancelled,
    mark_order_failed,
    mark_order_finished,
    mark_order_sent,
    mark_order_started,
    mark_step_reached,
    reassign_order,
    requeue_order,
    update_order_priority,
)
from orders.services.vehicle_events import emit_vehicle_changes
from orders.services.vehicles import (
    pause_vehicle,
    record_command_outcome,
    request_instant_action,
    resume_vehicle,
    send_vehicle_to_charge,
    send_vehicle_to_park,
)
from orders.services.webhooks import (
    attempt_webhook_delivery,
    create_webhook_subscription,
    delete_webhook_subscription,
    emit_event,
    enqueue_due_webhook_deliveries,
    ping_webhook_subscription,
    prune_webhook_deliveries,
    retry_webhook_deliveries,
    subscriptions_read_once,
)

__all__ = [
    "IdempotencyKeyInFlight",
    "StepSpec",
    "IdempotencyKeyReused",
    "StoredResponse",
    "attempt_webhook_delivery",
    "authenticate_api_token",
    "cancel_transport_order",
    "check_recurring_order",
    "claim_idempotency_key",
    "complete_idempotency_key",
    "checked_scopes",
    "create_integration_client",
    "create_due_recurring_orders",
    "create_transport_order",
    "create_webhook_subscription",
    "delete_webhook_subscription",
    "dispatch_pending_orders",
    "emit_event",
    "emit_vehicle_changes",
    "enqueue_due_webhook_deliveries",
    "issue_api_token",
    "mark_order_cancelled",
    "mark_order_failed",
    "mark_order_finished",
    "mark_order_sent",
    "mark_order_started",
    "mark_step_reached",
    "parse_steps",
    "pause_vehicle",
    "ping_webhook_subscription",
    "prune_idempotency_keys",
    "prune_webhook_deliveries",
    "reconcile_stale_assignments",
    "handle_lost_vehicles",
    "reassign_order",
    "release_idempotency_key",
    "record_command_outcome",
    "request_instant_action",
    "requeue_order",
    "resume_vehicle",
    "retry_webhook_deliveries",
    "revoke_api_token",
    "save_recurring_order",
    "send_vehicle_to_charge",
    "send_vehicle_to_park",
    "subscriptions_read_once",
    "update_order_priority",
]
