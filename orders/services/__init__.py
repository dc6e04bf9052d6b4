"""All writes of the orders app, re-exported from their modules:

- `transport`: create, reprioritise and cancel orders; progress reported by `control`
- `dispatch`: the assignment cycle and the reconciler of stale assignments
- `vehicles`: commands to vehicles, queued for `control`
- `webhooks`: subscriptions, deliveries and their attempts
- `clients`, `idempotency`: integration clients, API tokens, Idempotency-Key bookkeeping
"""

from orders.services.clients import (
    authenticate_api_token,
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
from orders.services.transport import (
    cancel_transport_order,
    create_transport_order,
    mark_order_cancelled,
    mark_order_failed,
    mark_order_finished,
    mark_order_sent,
    mark_order_started,
    mark_step_reached,
    requeue_order,
    update_order_priority,
)
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
)

__all__ = [
    "IdempotencyKeyInFlight",
    "IdempotencyKeyReused",
    "StoredResponse",
    "attempt_webhook_delivery",
    "authenticate_api_token",
    "cancel_transport_order",
    "claim_idempotency_key",
    "complete_idempotency_key",
    "create_integration_client",
    "create_transport_order",
    "create_webhook_subscription",
    "delete_webhook_subscription",
    "dispatch_pending_orders",
    "emit_event",
    "enqueue_due_webhook_deliveries",
    "issue_api_token",
    "mark_order_cancelled",
    "mark_order_failed",
    "mark_order_finished",
    "mark_order_sent",
    "mark_order_started",
    "mark_step_reached",
    "pause_vehicle",
    "ping_webhook_subscription",
    "prune_idempotency_keys",
    "prune_webhook_deliveries",
    "reconcile_stale_assignments",
    "release_idempotency_key",
    "record_command_outcome",
    "request_instant_action",
    "requeue_order",
    "resume_vehicle",
    "retry_webhook_deliveries",
    "revoke_api_token",
    "send_vehicle_to_charge",
    "send_vehicle_to_park",
    "update_order_priority",
]
