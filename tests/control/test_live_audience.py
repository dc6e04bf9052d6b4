"""Whether a browser has the live page open, as control asks before building its rows: the live
websockets mark themselves in Redis, or in the process in the embedded demo (no REDIS_URL)."""

import asyncio
from typing import Any

import pytest
import redis
from asgiref.sync import async_to_sync
from channels.testing import WebsocketCommunicator
from django.contrib.auth import get_user_model

from control import broadcasts
from control.broadcasts import VIEWERS_KEY, LiveAudience, LiveViewer
from control.consumers import LiveConsumer


@pytest.fixture
def redis_url(settings: Any) -> str:
    if not settings.REDIS_URL:
        pytest.skip("needs Redis (TEST_REDIS_URL)")
    redis.Redis.from_url(settings.REDIS_URL).delete(VIEWERS_KEY)  # no marks of other runs
    return str(settings.REDIS_URL)


@pytest.fixture
def in_process(settings: Any) -> None:
    """The embedded demo: no REDIS_URL, control runs in the web process."""
    settings.REDIS_URL = ""
    broadcasts._local_viewers.clear()


def _open_live_page(user: Any, after: float = 0.0) -> tuple[bool, bool]:
    """Connect a live websocket as `user` and close it again after `after` seconds: whether it
    was admitted, and whether control saw a live page open just before it closed."""

    async def scenario() -> tuple[bool, bool]:
        communicator = WebsocketCommunicator(LiveConsumer.as_asgi(), "/ws/live/")
        communicator.scope["user"] = user
        connected, _ = await communicator.connect()
        await asyncio.sleep(after)
        watched = LiveAudience().watching()
        await communicator.disconnect()
        return connected, watched

    return async_to_sync(scenario)()


@pytest.mark.django_db
@pytest.mark.usefixtures("redis_url")
def test_an_open_live_page_is_seen_through_redis_until_it_closes() -> None:
    boss = get_user_model().objects.create_superuser("boss", "boss@example.com", "x")
    assert not LiveAudience().watching()

    connected, watched = _open_live_page(boss)

    assert (connected, watched) == (True, True)
    assert not LiveAudience().watching()


@pytest.mark.django_db
@pytest.mark.usefixtures("in_process")
def test_an_open_live_page_is_seen_in_the_embedded_demo_without_redis() -> None:
    boss = get_user_model().objects.create_superuser("boss", "boss@example.com", "x")

    connected, watched = _open_live_page(boss)

    assert (connected, watched) == (True, True)
    assert not LiveAudience().watching()


@pytest.mark.django_db
@pytest.mark.usefixtures("in_process")
def test_a_refused_websocket_does_not_count_as_a_viewer() -> None:
    visitor = get_user_model().objects.create_user("visitor", password="x")

    connected, watched = _open_live_page(visitor)

    assert (connected, watched) == (False, False)


@pytest.mark.django_db
@pytest.mark.usefixtures("in_process")
def test_an_open_page_stays_counted_by_its_heartbeat(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(broadcasts, "VIEWER_TTL_S", 0.1)
    monkeypatch.setattr(broadcasts, "HEARTBEAT_S", 0.02)
    boss = get_user_model().objects.create_superuser("boss", "boss@example.com", "x")

    connected, watched = _open_live_page(boss, after=0.3)  # three times its first mark's life

    assert (connected, watched) == (True, True)


@pytest.mark.usefixtures("redis_url")
def test_a_mark_no_heartbeat_renewed_expires(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(broadcasts, "VIEWER_TTL_S", 0.05)  # as a web process that died leaves it
    viewer = LiveViewer("specific.dead-page")

    async def scenario() -> tuple[bool, bool]:
        await viewer.mark()
        fresh = LiveAudience().watching()
        await asyncio.sleep(0.1)
        lapsed = LiveAudience().watching()
        await viewer.end()
        return fresh, lapsed

    assert asyncio.run(scenario()) == (True, False)


def test_rows_are_built_while_redis_cannot_tell(settings: Any) -> None:
    settings.REDIS_URL = "redis://127.0.0.1:1/0"  # nothing listens there

    assert LiveAudience().watching()
