"""Admin pages for orders, clients, tokens, webhooks and commands."""

import pytest
from django.contrib.auth import get_user_model
from django.test import Client

from orders import services
from orders.models import ApiToken, IntegrationClient, WebhookDelivery, WebhookSubscription
from tests.factories import VehicleFactory


@pytest.fixture
def staff(db) -> Client:
    client = Client()
    client.force_login(get_user_model().objects.create_superuser("boss", password="x"))
    return client


@pytest.mark.parametrize(
    "model",
    [
        "transportorder",
        "integrationclient",
        "apitoken",
        "webhooksubscription",
        "webhookdelivery",
        "idempotencykey",
        "vehiclecommand",
    ],
)
def test_every_list_page_renders(staff, model, erp, demo_map) -> None:
    services.create_webhook_subscription(client=erp, url="http://127.0.0.1:9/", events=["*"])
    services.pause_vehicle(vehicle=VehicleFactory())
    services.create_transport_order(
        source=demo_map.stations.get(station_id="PICK-1"),
        destination=demo_map.stations.get(station_id="DROP-1"),
    )

    assert staff.get(f"/admin/orders/{model}/").status_code == 200


def test_a_client_made_in_the_admin_gets_a_user_and_a_token_shown_once(staff) -> None:
    staff.post(
        "/admin/orders/integrationclient/add/",
        {"name": "sap", "is_active": "on", "tokens-TOTAL_FORMS": 0, "tokens-INITIAL_FORMS": 0},
    )
    client = IntegrationClient.objects.get(name="sap")

    page = staff.post(
        "/admin/orders/integrationclient/",
        {"action": "issue_token", "_selected_action": [client.pk]},
        follow=True,
    )

    token = ApiToken.objects.get(client=client)
    assert client.user.username == "client:sap"
    assert f"Token for sap: {token.prefix}" in page.content.decode()
    staff.post("/admin/orders/apitoken/", {"action": "revoke", "_selected_action": [token.pk]})
    token.refresh_from_db()
    assert token.revoked_at is not None


def test_a_subscription_made_in_the_admin_gets_a_secret(staff, erp) -> None:
    staff.post(
        "/admin/orders/webhooksubscription/add/",
        {
            "client": erp.pk,
            "url": "http://127.0.0.1:9/hook",
            "events": '["order.finished"]',
            "is_active": "on",
        },
    )

    assert WebhookSubscription.objects.get().secret.startswith("whsec_")


def test_failed_deliveries_can_be_sent_again(
    staff, erp, django_capture_on_commit_callbacks
) -> None:
    subscription = services.create_webhook_subscription(
        client=erp, url="http://127.0.0.1:9/", events=["*"]
    )
    delivery = services.ping_webhook_subscription(subscription=subscription)
    WebhookDelivery.objects.update(status=WebhookDelivery.Status.FAILED, attempts=8)

    staff.post(
        "/admin/orders/webhookdelivery/",
        {"action": "retry_now", "_selected_action": [delivery.pk]},
    )

    delivery.refresh_from_db()
    assert (delivery.status, delivery.attempts) == (WebhookDelivery.Status.PENDING, 0)
