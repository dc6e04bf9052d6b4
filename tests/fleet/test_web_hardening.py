"""Web hardening: login lockout, API throttling per integration client, request size limit."""

import json

import pytest
from django.contrib.auth import get_user_model
from django.core.cache import cache
from django.test import Client
from rest_framework.test import APIClient
from rest_framework.throttling import SimpleRateThrottle

from orders.models import TransportOrder
from orders.services import create_integration_client, issue_api_token

pytestmark = pytest.mark.django_db


def admin_login(client: Client, username: str, password: str) -> int:
    response = client.post(
        "/admin/login/?next=/admin/",
        {"username": username, "password": password},
        REMOTE_ADDR="10.0.0.7",
    )
    return response.status_code


def test_repeated_failed_logins_lock_that_user_name_out(settings) -> None:
    get_user_model().objects.create_superuser("chief", password="right-horse-battery")
    get_user_model().objects.create_superuser("other", password="right-horse-battery")
    client = Client()
    for _ in range(settings.AXES_FAILURE_LIMIT - 1):
        assert admin_login(client, "chief", "wrong") == 200  # the form again, with an error
    assert admin_login(client, "chief", "wrong") == 429
    # Now even the right password is refused for that user name from that address...
    assert admin_login(Client(), "chief", "right-horse-battery") == 429
    # ...while another user from the same address logs in (302 to the admin).
    assert admin_login(Client(), "other", "right-horse-battery") == 302


def test_a_successful_login_resets_the_failure_count() -> None:
    get_user_model().objects.create_superuser("chief", password="right-horse-battery")
    for _ in range(3):
        assert admin_login(Client(), "chief", "wrong") == 200
    assert admin_login(Client(), "chief", "right-horse-battery") == 302
    for _ in range(3):
        assert admin_login(Client(), "chief", "wrong") == 200  # counting starts again


def test_integration_clients_are_throttled_each_on_their_own(monkeypatch) -> None:
    monkeypatch.setattr(SimpleRateThrottle, "THROTTLE_RATES", {"user": "3/min", "anon": "3/min"})
    cache.clear()
    clients = []
    for name in ("erp", "wms"):
        _, key = issue_api_token(
            client=create_integration_client(name=name, scopes=["orders:read"])
        )
        api = APIClient()
        api.credentials(HTTP_AUTHORIZATION=f"Bearer {key}")
        clients.append(api)
    erp, wms = clients
    assert [erp.get("/api/v1/orders/").status_code for _ in range(3)] == [200, 200, 200]
    refused = erp.get("/api/v1/orders/")
    assert refused.status_code == 429
    assert int(refused["Retry-After"]) > 0
    assert "throttled" in refused.json()["detail"].lower()
    assert wms.get("/api/v1/orders/").status_code == 200  # the other client is not affected


def test_an_oversized_request_body_is_refused_before_it_is_parsed(settings) -> None:
    settings.DATA_UPLOAD_MAX_MEMORY_SIZE = 10_000
    _, key = issue_api_token(client=create_integration_client(name="erp", scopes=["orders:write"]))
    api = APIClient()
    api.credentials(HTTP_AUTHORIZATION=f"Bearer {key}")
    body = json.dumps({"source": "PICK-1", "destination": "DROP-1", "note": "x" * 20_000})
    response = api.post("/api/v1/orders/", body, content_type="application/json")
    assert response.status_code == 400  # Django's RequestDataTooBig, before any parsing
    assert not TransportOrder.objects.exists()
