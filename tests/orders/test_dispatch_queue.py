"""Coalesced dispatch requests: one queued cycle however many writes ask, with real Redis."""

from collections.abc import Iterator

import pytest
import redis
from django.conf import settings

from control.persistence import DjangoStore
from orders import services
from orders.models import TransportOrder
from orders.services import dispatch_queue
from orders.services.dispatch_queue import FLAG_KEY, FLAG_TTL
from orders.tasks import dispatch_pending_orders_task
from tests.factories import VehicleFactory

needs_redis = pytest.mark.skipif(not settings.REDIS_URL, reason="needs Redis (TEST_REDIS_URL)")


@pytest.fixture
def flag() -> Iterator[redis.Redis]:
    """The real Redis holding the flag, without a flag before or after the test (a leftover
    would silence the dispatch requests of the tests that follow)."""
    client = redis.Redis.from_url(settings.REDIS_URL)
    client.delete(FLAG_KEY)
    yield client
    client.delete(FLAG_KEY)


@pytest.fixture
def queued(monkeypatch: pytest.MonkeyPatch) -> list[str]:
    """The dispatch tasks queued (recorded instead of sent to the broker)."""
    tasks: list[str] = []
    monkeypatch.setattr(dispatch_pending_orders_task, "delay", lambda: tasks.append("dispatch"))
    return tasks


@needs_redis
def test_requests_while_a_cycle_is_queued_queue_one_task(flag, queued) -> None:
    for _ in range(25):
        dispatch_queue.request_dispatch()

    assert queued == ["dispatch"]
    assert 0 < flag.ttl(FLAG_KEY) <= FLAG_TTL  # a lost task cannot silence dispatch for good


@needs_redis
def test_control_asks_through_the_same_flag(flag, queued) -> None:
    store = DjangoStore()

    dispatch_queue.request_dispatch()
    store.request_dispatch()
    store.request_dispatch()

    assert queued == ["dispatch"]


@needs_redis
def test_the_task_clears_the_flag_before_its_cycle(flag, queued, station, monkeypatch) -> None:
    VehicleFactory()
    order = TransportOrder.objects.create(source=station("PICK-1"), destination=station("DROP-1"))
    dispatch_queue.request_dispatch()
    seen: list[bool] = []
    cycle = services.dispatch_pending_orders

    def observed_cycle() -> list[TransportOrder]:
        seen.append(bool(flag.exists(FLAG_KEY)))
        dispatch_queue.request_dispatch()  # an order arriving during the cycle ...
        dispatch_queue.request_dispatch()
        return cycle()

    monkeypatch.setattr(services, "dispatch_pending_orders", observed_cycle)

    assert dispatch_pending_orders_task() == 1

    order.refresh_from_db()
    assert order.status == TransportOrder.Status.ASSIGNED
    assert seen == [False]
    assert queued == ["dispatch", "dispatch"]  # ... queues exactly one more cycle


@needs_redis
def test_a_request_after_the_cycle_started_queues_again(flag, queued) -> None:
    dispatch_queue.request_dispatch()
    dispatch_queue.start_cycle()
    dispatch_queue.request_dispatch()

    assert queued == ["dispatch", "dispatch"]


@needs_redis
def test_a_broker_failure_clears_the_flag_so_the_next_request_tries_again(
    flag, monkeypatch
) -> None:
    attempts: list[str] = []

    def broker_down() -> None:
        attempts.append("dispatch")
        raise ConnectionError("broker down")

    monkeypatch.setattr(dispatch_pending_orders_task, "delay", broker_down)

    for _ in range(2):
        with pytest.raises(ConnectionError):
            dispatch_queue.request_dispatch()

    assert attempts == ["dispatch", "dispatch"]
    assert not flag.exists(FLAG_KEY)


def test_without_redis_every_request_queues(settings, queued) -> None:
    settings.REDIS_URL = ""

    for _ in range(3):
        dispatch_queue.request_dispatch()
    dispatch_queue.start_cycle()

    assert queued == ["dispatch"] * 3


def test_when_redis_fails_every_request_still_queues(settings, queued) -> None:
    settings.REDIS_URL = "redis://127.0.0.1:1/0"  # nothing listens on port 1

    for _ in range(3):
        dispatch_queue.request_dispatch()
    dispatch_queue.start_cycle()  # logs and goes on

    assert queued == ["dispatch"] * 3


def test_without_redis_a_new_order_is_dispatched_at_once(
    settings, station, django_capture_on_commit_callbacks
) -> None:
    settings.REDIS_URL = ""  # the embedded demo: eager tasks, no flag
    vehicle = VehicleFactory()

    with django_capture_on_commit_callbacks(execute=True):
        first = services.create_transport_order(
            source=station("PICK-1"), destination=station("DROP-1")
        )
    with django_capture_on_commit_callbacks(execute=True):
        services.create_transport_order(source=station("PICK-2"), destination=station("DROP-1"))

    first.refresh_from_db()
    assert first.vehicle == vehicle
    assert TransportOrder.objects.filter(status=TransportOrder.Status.NEW).count() == 1


@needs_redis
def test_with_redis_each_new_order_is_dispatched_and_the_flag_cleared(
    flag, station, django_capture_on_commit_callbacks
) -> None:
    VehicleFactory()
    VehicleFactory()

    for pick in ("PICK-1", "PICK-2"):  # eager tasks: each request runs its cycle at once
        with django_capture_on_commit_callbacks(execute=True):
            services.create_transport_order(source=station(pick), destination=station("DROP-1"))

    assert TransportOrder.objects.filter(status=TransportOrder.Status.ASSIGNED).count() == 2
    assert not flag.exists(FLAG_KEY)
