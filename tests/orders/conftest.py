"""Fixtures of the orders tests: an integration client with a token, API clients, stations."""

from typing import Any

import pytest
from rest_framework.test import APIClient

from fleet.roles import ALL_API_SCOPES
from maps.models import Map, Station
from orders import services
from orders.models import IntegrationClient


@pytest.fixture(autouse=True)
def sent_commands(monkeypatch: pytest.MonkeyPatch) -> list[tuple[str, dict[str, Any]]]:
    """Commands the services queue for control, kept here instead of going to Redis."""
    sent: list[tuple[str, dict[str, Any]]] = []
    for module in ("transport", "dispatch", "vehicles"):
        monkeypatch.setattr(
            f"orders.services.{module}.send_command",
            lambda kind, **payload: sent.append((kind, payload)),
        )
    return sent


@pytest.fixture
def erp(db: None) -> IntegrationClient:
    return services.create_integration_client(name="erp", scopes=ALL_API_SCOPES)


@pytest.fixture
def erp_key(erp: IntegrationClient) -> str:
    return services.issue_api_token(client=erp)[1]


@pytest.fixture
def api(erp_key: str) -> APIClient:
    """An API client that authenticates as the `erp` integration client with its token."""
    client = APIClient()
    client.credentials(HTTP_AUTHORIZATION=f"Bearer {erp_key}")
    return client


@pytest.fixture
def station(demo_map: Map):  # type: ignore[no-untyped-def]
    def find(station_id: str) -> Station:
        return Station.objects.get(map=demo_map, station_id=station_id)

    return find
