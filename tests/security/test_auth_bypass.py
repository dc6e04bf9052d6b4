"""Schemathesis looks for an authentication bypass: every operation of the OpenAPI schema, with
generated input, called with no token, with a wrong token, and with a token that holds every
scope except the one the operation needs. Each call must be refused (401/403), never 2xx."""

from typing import Any

import pytest
import schemathesis
from django.core import signals
from django.core.handlers.wsgi import WSGIHandler
from django.db import close_old_connections
from django.urls import Resolver404, resolve
from django.utils import timezone
from hypothesis import HealthCheck, Phase, given, settings
from schemathesis import Case, GenerationMode

from fleet import roles
from fleet.api_access import rule_for
from maps.demo import warehouse_layout
from maps.services import create_layout
from orders import services
from tests.factories import VehicleFactory
from tests.security.conftest import count

EXAMPLES_PER_OPERATION = 4
WRONG_TOKEN = {"Authorization": "Bearer oft_this-is-not-a-token-of-anyone-0000000000"}


@pytest.fixture(autouse=True)
def keep_the_test_connection() -> Any:
    """Requests through the bare WSGI handler would close the test's database connection."""
    signals.request_started.disconnect(close_old_connections)
    signals.request_finished.disconnect(close_old_connections)
    yield
    signals.request_started.connect(close_old_connections)
    signals.request_finished.connect(close_old_connections)


def _bearer(scopes: list[str], name: str) -> dict[str, str]:
    client = services.create_integration_client(name=name, scopes=scopes)
    return {"Authorization": f"Bearer {services.issue_api_token(client=client)[1]}"}


@pytest.fixture
def fleet_with_clients(db: None) -> tuple[Any, dict[str, dict[str, str]]]:
    """Objects to hit (ids 1, 2, …), the schema, and per scope a token lacking only that one."""
    layout = create_layout(spec=warehouse_layout(columns=6, rows=4))
    for node in ("A1.1", "A2.2"):
        VehicleFactory(last_node_id=node, last_seen=timezone.now())
    stations = {s.station_id: s for s in layout.stations.all()}
    full = _bearer(list(roles.ALL_API_SCOPES), "full")
    owner = services.create_integration_client(name="owner", scopes=list(roles.ALL_API_SCOPES))
    services.create_webhook_subscription(client=owner, url="http://127.0.0.1:9/", events=["*"])
    services.create_transport_order(
        source=stations["PICK-1"], destination=stations["DROP-1"], created_by=owner.user
    )
    lacking = {
        scope: _bearer([s for s in roles.ALL_API_SCOPES if s != scope], f"lacks-{scope}")
        for scope in roles.ALL_API_SCOPES
    }
    schema = schemathesis.openapi.from_wsgi(
        "/api/v1/schema/?format=json", WSGIHandler(), headers=full
    )
    return schema, lacking


def _needed_scope(case: Case) -> str | None:
    try:
        match = resolve(case.formatted_path)
    except Resolver404:
        return None
    rule = rule_for(match.url_name, case.method.upper())
    return rule.scope if rule else None


def test_no_operation_answers_without_the_right_token(fleet_with_clients: Any) -> None:
    schema, lacking = fleet_with_clients
    operations = [result.ok() for result in schema.get_all_operations()]
    bypasses: list[str] = []
    calls = {"refused": 0, "not routed": 0}

    for operation in operations:

        @given(case=operation.as_strategy(generation_mode=GenerationMode.POSITIVE))
        @settings(
            max_examples=EXAMPLES_PER_OPERATION,
            deadline=None,
            suppress_health_check=list(HealthCheck),
            derandomize=True,
            database=None,
            phases=[Phase.explicit, Phase.generate],
        )
        def attempt(case: Case) -> None:
            scope = _needed_scope(case)
            attempts = {"no token": {}, "wrong token": WRONG_TOKEN}
            if scope is not None:
                attempts[f"token without {scope}"] = lacking[scope]
            for label, headers in attempts.items():
                case.headers = {
                    k: v for k, v in (case.headers or {}).items() if k.lower() != "authorization"
                }
                status = case.call(headers=headers).status_code
                if scope is None and status == 404:
                    calls["not routed"] += 1  # the generated path matches no URL
                elif status in (401, 403):
                    calls["refused"] += 1
                else:
                    bypasses.append(f"{case.method} {case.formatted_path} ({label}): {status}")

        attempt()

    count("schemathesis: unauthorised calls refused", calls["refused"])
    assert len(operations) >= 50
    assert calls["refused"] >= len(operations) * 2
    assert not bypasses, "\n".join(sorted(set(bypasses)))
