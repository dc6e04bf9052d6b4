"""Fixtures of the maintenance tests."""

from typing import Any

import pytest

from maintenance import services
from maps.models import Map, Station


@pytest.fixture(autouse=True)
def sent_commands(monkeypatch: pytest.MonkeyPatch) -> list[tuple[str, dict[str, Any]]]:
    sent: list[tuple[str, dict[str, Any]]] = []
    for target in (
        "orders.services.dispatch.send_command",
        "orders.services.transport.send_command",
    ):
        monkeypatch.setattr(target, lambda kind, **payload: sent.append((kind, payload)))
    return sent


@pytest.fixture(autouse=True)
def fresh_observer() -> None:
    services.OBSERVER.tracks.clear()


@pytest.fixture
def station(demo_map: Map):  # type: ignore[no-untyped-def]
    def find(station_id: str) -> Station:
        return Station.objects.get(map=demo_map, station_id=station_id)

    return find
