"""Models of the orders app: transport orders, integration clients, webhooks, vehicle commands."""

from orders.models.commands import VehicleCommand
from orders.models.integrations import ApiToken, IdempotencyKey, IntegrationClient
from orders.models.schedules import RecurringOrder, RecurringOrderRun
from orders.models.transport import OrderEvent, OrderSequence, OrderStep, TransportOrder
from orders.models.webhooks import WebhookAttempt, WebhookDelivery, WebhookSubscription

__all__ = [
    "ApiToken",
    "IdempotencyKey",
    "IntegrationClient",
    "OrderEvent",
    "OrderSequence",
    "OrderStep",
    "RecurringOrder",
    "RecurringOrderRun",
    "TransportOrder",
    "VehicleCommand",
    "WebhookAttempt",
    "WebhookDelivery",
    "WebhookSubscription",
]
