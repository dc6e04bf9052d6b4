"""The live websocket admits only logged-in users who may view operations."""

import json
from typing import Any

import pytest
from asgiref.sync import async_to_sync
from channels.layers import get_channel_layer
from channels.testing import WebsocketCommunicator
from django.contrib.auth import get_user_model
from django.contrib.auth.models import AnonymousUser

from control.consumers import NOT_LOGGED_IN, NOT_PERMITTED, LiveConsumer
from fleet.realtime import LIVE_GROUP, encode_event

pytestmark = pytest.mark.django_db


def _connect(user: Any) -> tuple[bool, Any, dict[str, Any] | None]:
    """Connect as `user`; when admitted, broadcast one event and return what arrived."""

    async def scenario() -> tuple[bool, Any, dict[str, Any] | None]:
        communicator = WebsocketCommunicator(LiveConsumer.as_asgi(), "/ws/live/")
        communicator.scope["user"] = user
        connected, code = await communicator.connect()
        received = None
        if connected:
            await get_channel_layer().group_send(
                LIVE_GROUP,
                {"type": "fleet.event", "event": "vehicles.update", "payload": {"vehicles": []}},
            )
            received = await communicator.receive_json_from(timeout=5)
            await communicator.disconnect()
        return connected, code, received

    return async_to_sync(scenario)()


def test_anonymous_is_refused_as_not_logged_in() -> None:
    assert _connect(AnonymousUser())[:2] == (False, NOT_LOGGED_IN)


def test_user_without_view_operations_is_refused() -> None:
    user = get_user_model().objects.create_user("visitor", password="x")
    assert _connect(user)[:2] == (False, NOT_PERMITTED)


def test_user_who_may_view_operations_gets_the_fleet_events() -> None:
    user = get_user_model().objects.create_superuser("boss", "boss@example.com", "x")
    connected, _, received = _connect(user)
    assert connected
    assert received == {"event": "vehicles.update", "payload": {"vehicles": []}}


def test_an_event_encoded_once_is_forwarded_as_it_is() -> None:
    user = get_user_model().objects.create_superuser("boss", "boss@example.com", "x")
    text = encode_event("vehicles.update", {"vehicles": [{"id": 1, "x": 0.0}]})

    async def scenario() -> str:
        communicator = WebsocketCommunicator(LiveConsumer.as_asgi(), "/ws/live/")
        communicator.scope["user"] = user
        connected, _ = await communicator.connect()
        assert connected
        await get_channel_layer().group_send(LIVE_GROUP, {"type": "fleet.json", "text": text})
        received: str = await communicator.receive_from(timeout=5)
        await communicator.disconnect()
        return received

    received = async_to_sync(scenario)()
    assert received == text
    assert json.loads(received) == {
        "event": "vehicles.update",
        "payload": {"vehicles": [{"id": 1, "x": 0.0}]},
    }


def test_live_page_and_its_json_need_view_operations(client: Any) -> None:
    user = get_user_model().objects.create_user("visitor", password="x")
    client.force_login(user)
    for url in ("/", "/live/vehicles.json", "/live/orders.json"):
        assert client.get(url).status_code == 403, url
    user.is_superuser = True
    user.save()
    for url in ("/", "/live/vehicles.json", "/live/orders.json"):
        assert client.get(url).status_code == 200, url
