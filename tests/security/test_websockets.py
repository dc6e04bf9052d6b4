"""Websockets per role: every route of fleet.routing against every principal, through the
application's own stack (origin check, session auth, URL router) for the origin test."""

from typing import Any

import pytest
from asgiref.sync import async_to_sync
from channels.routing import URLRouter
from channels.testing import WebsocketCommunicator
from django.contrib.auth.models import AnonymousUser

from fleet import roles
from fleet.routing import websocket_urlpatterns
from tests.security.conftest import PRINCIPALS, count

# route pattern → the permission a user needs to connect
WEBSOCKETS = {
    "ws/live/": roles.VIEW_OPERATIONS,
    "ws/vehicles/<int:pk>/": roles.VIEW_OPERATIONS,
}
SAMPLE_PATHS = {"ws/live/": "/ws/live/", "ws/vehicles/<int:pk>/": "/ws/vehicles/1/"}


@pytest.fixture(autouse=True)
def no_watch_commands(monkeypatch: pytest.MonkeyPatch) -> None:
    """The vehicle consumer asks control to watch the vehicle; here nothing goes to Redis."""
    monkeypatch.setattr("control.vehicle_consumers.send_command", lambda *a, **k: None)


def test_every_websocket_route_has_an_expectation() -> None:
    routes = {str(pattern.pattern) for pattern in websocket_urlpatterns}

    assert routes - set(WEBSOCKETS) == set(), (
        "Websocket routes without an expectation in tests/security/test_websockets.py "
        f"WEBSOCKETS (check the permission in the consumer's connect): {routes - set(WEBSOCKETS)}"
    )
    assert set(WEBSOCKETS) - routes == set(), "WEBSOCKETS names routes that no longer exist"


def _connects(user: Any, path: str) -> tuple[bool, Any]:
    async def scenario() -> tuple[bool, Any]:
        communicator = WebsocketCommunicator(URLRouter(websocket_urlpatterns), path)
        communicator.scope["user"] = user if user is not None else AnonymousUser()
        connected, code = await communicator.connect()
        if connected:
            await communicator.disconnect()
        return connected, code

    return async_to_sync(scenario)()


@pytest.mark.django_db(transaction=True)
def test_websocket_connect_per_role(principals: dict[str, Any]) -> None:
    wrong: list[str] = []
    for principal in PRINCIPALS:
        user = principals[principal]
        for route, permission in WEBSOCKETS.items():
            connected, code = _connects(user, SAMPLE_PATHS[route])
            should = user is not None and user.has_perm(permission)
            if connected != should:
                wrong.append(f"{principal} on {route}: connected={connected} (close {code})")

    count("websockets: principal × route", len(PRINCIPALS) * len(WEBSOCKETS))
    assert not wrong, "\n".join(wrong)


@pytest.mark.django_db(transaction=True)
def test_a_websocket_from_a_foreign_origin_is_refused(principals: dict[str, Any]) -> None:
    """The ASGI application checks the Origin against ALLOWED_HOSTS before any consumer runs
    (cross-site websocket hijacking: a page elsewhere riding on the user's session cookie)."""
    from django.test import Client

    from fleet.asgi import application

    browser = Client()
    browser.force_login(principals[roles.OPERATOR])
    cookie = f"sessionid={browser.cookies['sessionid'].value}".encode()

    async def scenario(origin: bytes) -> bool:
        headers = [(b"origin", origin), (b"host", b"testserver"), (b"cookie", cookie)]
        communicator = WebsocketCommunicator(application, "/ws/live/", headers=headers)
        connected, _ = await communicator.connect()
        if connected:
            await communicator.disconnect()
        return connected

    assert async_to_sync(scenario)(b"http://testserver") is True
    assert async_to_sync(scenario)(b"http://evil.example") is False
