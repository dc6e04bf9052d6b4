"""The OpenAPI schema, its locally served docs, and a bounded schemathesis run against it."""

import re
from typing import Any

import pytest
import schemathesis
from django.core import signals
from django.core.handlers.wsgi import WSGIHandler
from django.db import close_old_connections
from django.test import Client
from django.utils import timezone
from hypothesis import HealthCheck, Phase, given, settings
from hypothesis import strategies as st
from schemathesis import Case, GenerationMode
from schemathesis.checks import not_a_server_error
from schemathesis.specs.openapi.checks import (
    content_type_conformance,
    response_schema_conformance,
    status_code_conformance,
)

from fleet.roles import ALL_API_SCOPES
from maps.demo import warehouse_layout
from maps.services import create_layout
from orders import services
from orders.models import TransportOrder
from tests.factories import VehicleFactory


def test_schema_describes_every_endpoint_with_token_auth(api) -> None:
    schema = api.get("/api/v1/schema/", HTTP_ACCEPT="application/vnd.oai.openapi+json").json()

    assert schema["openapi"].startswith("3.")
    assert set(schema["paths"]) >= {
        "/api/v1/orders/",
        "/api/v1/orders/{id}/",
        "/api/v1/orders/{id}/cancel/",
        "/api/v1/orders/{id}/priority/",
        "/api/v1/vehicles/",
        "/api/v1/vehicles/{id}/",
        "/api/v1/vehicles/{id}/pause/",
        "/api/v1/vehicles/{id}/resume/",
        "/api/v1/vehicles/{id}/charge/",
        "/api/v1/vehicles/{id}/park/",
        "/api/v1/vehicles/{id}/instant-actions/",
        "/api/v1/webhooks/",
        "/api/v1/webhooks/{id}/",
        "/api/v1/webhooks/{id}/ping/",
        "/api/v1/stations/",
        "/api/v1/maps/",
    }
    assert schema["components"]["securitySchemes"]["clientToken"]["scheme"] == "bearer"
    create = schema["paths"]["/api/v1/orders/"]["post"]
    assert "Idempotency-Key" in [p["name"] for p in create["parameters"]]
    listing = schema["paths"]["/api/v1/orders/"]["get"]
    assert {"status", "vehicle", "source", "created_after", "limit", "offset"} <= {
        p["name"] for p in listing["parameters"]
    }


@pytest.mark.parametrize("page", ["/api/v1/docs/", "/api/v1/redoc/"])
def test_docs_are_served_from_the_app_without_a_cdn(api, page) -> None:
    response = api.get(page)

    html = response.content.decode()
    assets = re.findall(r'(?:src|href)="(/static/[^"]+)"', html)
    assert response.status_code == 200
    assert "cdn" not in html.lower()
    assert "https://" not in html
    assert any("drf_spectacular_sidecar" in asset for asset in assets)
    for asset in assets:
        assert Client().get(asset).status_code == 200, asset


def test_redoc_may_load_images_from_the_app_only(api) -> None:
    """The Redoc bundle's footer fetches its logo from cdn.redoc.ly; the page forbids it."""
    response = api.get("/api/v1/redoc/")

    assert response.status_code == 200
    assert response["Content-Security-Policy"] == "img-src 'self' data:"


def test_schema_and_docs_need_a_login(db) -> None:
    from rest_framework.test import APIClient

    assert APIClient().get("/api/v1/schema/").status_code == 401


@pytest.fixture
def fuzzed_api(db, monkeypatch):
    """A schema loaded from the app, with data for the fuzzer to hit and a client token."""
    monkeypatch.setattr(
        "orders.services.webhooks._post", lambda *a: pytest.fail("no webhook may leave the test")
    )
    monkeypatch.setattr("orders.services.vehicles.send_command", lambda *a, **k: None)
    monkeypatch.setattr("orders.services.transport.send_command", lambda *a, **k: None)
    monkeypatch.setattr("orders.services.dispatch.send_command", lambda *a, **k: None)
    layout = create_layout(spec=warehouse_layout(columns=6, rows=4))
    for node in ("A1.1", "A2.2", "A4.1"):
        VehicleFactory(last_node_id=node, last_seen=timezone.now())
    client = services.create_integration_client(name="fuzzer", scopes=ALL_API_SCOPES)
    key = services.issue_api_token(client=client)[1]
    stations = {s.station_id: s for s in layout.stations.all()}
    for pick, drop in (("PICK-1", "DROP-1"), ("PICK-2", "DROP-3")):
        services.create_transport_order(
            source=stations[pick], destination=stations[drop], created_by=client.user
        )
    TransportOrder.objects.create(
        source=stations["PICK-3"], destination=stations["DROP-2"], status="FINISHED"
    )
    services.create_webhook_subscription(client=client, url="http://127.0.0.1:9/", events=["*"])
    headers = {"Authorization": f"Bearer {key}"}
    schema = schemathesis.openapi.from_wsgi(
        "/api/v1/schema/?format=json", WSGIHandler(), headers=headers
    )
    return schema, headers


@pytest.fixture(autouse=True)
def keep_the_test_connection():
    """Requests through the bare WSGI handler would close the database connection at their end
    (and with it the test's transaction); Django's test client avoids that the same way."""
    signals.request_started.disconnect(close_old_connections)
    signals.request_finished.disconnect(close_old_connections)
    yield
    signals.request_started.connect(close_old_connections)
    signals.request_finished.connect(close_old_connections)


OWN_PATHS = ("/api/v1/orders/", "/api/v1/vehicles/", "/api/v1/webhooks/")
CHECKS = [
    not_a_server_error,
    status_code_conformance,
    content_type_conformance,
    response_schema_conformance,
]


def fuzz(strategy: Any, examples: int, headers: dict[str, str], checks: list[Any]) -> None:
    @given(case=strategy)
    @settings(
        max_examples=examples,
        deadline=None,
        suppress_health_check=list(HealthCheck),
        derandomize=True,
        database=None,
        phases=[Phase.explicit, Phase.generate],
    )
    def call(case: Case) -> None:
        case.call_and_validate(headers=headers, checks=checks)

    call()


# Rerun: a database refusing connections under load answers 503; derandomized,
# so a real 5xx fails every run.
@pytest.mark.flaky(reruns=2, reruns_delay=5)
@pytest.mark.parametrize(
    ("mode", "examples"), [(GenerationMode.POSITIVE, 25), (GenerationMode.NEGATIVE, 15)]
)
def test_the_api_gives_no_server_error_for_any_input(fuzzed_api, mode, examples) -> None:
    """Every operation, with valid (then invalid) generated input: never a 5xx. Valid input to
    the endpoints of this app (orders, vehicles, webhooks) also gets answers that match the
    schema (status code, content type, body)."""
    schema, headers = fuzzed_api
    failures: dict[str, str] = {}
    operations = [result.ok() for result in schema.get_all_operations()]

    for operation in operations:
        ours = operation.path.startswith(OWN_PATHS)
        checks = CHECKS if mode is GenerationMode.POSITIVE and ours else [not_a_server_error]
        try:
            strategies = [operation.as_strategy(generation_mode=mode)]
            if mode is GenerationMode.POSITIVE:
                strategies += schema.get_strategies_from_examples(operation)
            fuzz(st.one_of(strategies), examples, headers, checks)
        except Exception as error:  # collect all operations' failures, then report them
            failures[operation.label] = str(error)[:2000]

    assert len(operations) >= 25
    assert not failures, "\n\n".join(f"{label}:\n{text}" for label, text in failures.items())
