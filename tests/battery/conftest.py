"""Fixtures of the battery tests: the demo warehouse with its two chargers, captured commands."""

from typing import Any

import pytest

from battery import services
from battery.models import Charger
from maps.models import Map, Station


@pytest.fixture(autouse=True)
def sent_commands(monkeypatch: pytest.MonkeyPatch) -> list[tuple[str, dict[str, Any]]]:
    """Commands for control, kept here instead of going to Redis."""
    sent: list[tuple[str, dict[str, Any]]] = []
    for target in (
        "battery.services.charging.send_command",
        "orders.services.dispatch.send_command",
        "orders.services.transport.send_command",
    ):
        monkeypatch.setattr(target, lambda kind, **payload: sent.append((kind, payload)))
    return sent


@pytest.fixture(autouse=True)
def fresh_observer() -> None:
    """The observer remembers vehicles between flushes; each test starts without memory."""
    services.OBSERVER.tracks.clear()


@pytest.fixture
def station(demo_map: Map):  # type: ignore[no-untyped-def]
    def find(station_id: str) -> Station:
        return Station.objects.get(map=demo_map, station_id=station_id)

    return find


@pytest.fixture
def chargers(demo_map: Map) -> list[Charger]:
    """CHARGE-1 (at A5.1) and CHARGE-2 (at A5.3), one point each."""
    return [
        Charger.objects.create(station=s)
        for s in Station.objects.filter(map=demo_map, kind=Station.Kind.CHARGE).order_by(
            "station_id"
        )
    ]
