"""`order.assigned` starts the named orders at once (issue 11): control's command thread reads
only those orders, not every active one, and does not wait for the main thread's periodic work."""

import json
import threading
import time
from dataclasses import dataclass, field
from typing import Any

import pytest
from django.db import connections

from control.controller import Controller
from control.ports import ActiveOrder, FlushBatch
from control.runner import ControlLoop, assigned_jobs, names_assigned
from tests.control.fakes import FakeStore, order, state, topic

pytestmark = pytest.mark.django_db  # the loop's registry refresh reads map releases

QUIET = {  # after the first round no timer is due again: only commands move the loop
    "SYNC_INTERVAL": 3600.0,
    "FLUSH_INTERVAL": 3600.0,
    "BROADCAST_INTERVAL": 3600.0,
    "REGISTRY_INTERVAL": 3600.0,
}
ASSIGNED = {"kind": "order.assigned", "orders": [7]}


@dataclass
class CountingStore(FakeStore):
    """The fake store, counting the full re-reads and the reads of named orders."""

    full_reads: int = 0
    named_reads: list[list[int]] = field(default_factory=list)
    synced: threading.Event = field(default_factory=threading.Event)

    def active_orders(self) -> list[ActiveOrder]:
        self.full_reads += 1
        self.synced.set()
        return self.orders

    def assigned_orders(
        self, *, orders: list[int], charge_sessions: list[int], moves: list[int]
    ) -> list[ActiveOrder]:
        self.named_reads.append(orders)
        return [o for o in self.orders if o.transport_order_id in orders]


class NoLink:
    """The MQTT link, without a broker (the controller publishes to the test's callback)."""

    def start(self) -> None: ...

    def stop(self) -> None: ...


class Control:
    """A control loop in a thread with one idle vehicle at `a`; commands are handed to it with
    `send`, and `sent` collects the orders it publishes."""

    def __init__(self, store: FakeStore, intervals: dict[str, float] = QUIET) -> None:
        self.store = store
        self.sent: list[str] = []
        self.published = threading.Event()
        self.queue: list[dict[str, Any]] = []
        self.controller = Controller(store=store, interface_name="uagv", publish=self.publish)
        self.loop = ControlLoop(
            self.controller,
            NoLink(),  # type: ignore[arg-type]
            receive_commands=self.receive,
            broadcast=lambda rows: None,
            intervals=intervals,
        )
        self.controller.load()
        self.controller.handle_message(topic(), state(last_node="a"))
        self.thread = threading.Thread(target=self.run, daemon=True)

    def run(self) -> None:
        try:
            self.loop.run()
        finally:
            connections.close_all()  # the loop thread's own (the registry refresh reads)

    def publish(self, topic_text: str, payload: bytes, qos: int) -> None:
        if topic_text.endswith("/order"):
            self.sent.append(json.loads(payload)["orderId"])
            self.published.set()

    def receive(self, timeout: float) -> list[dict[str, Any]]:
        taken, self.queue = self.queue, []
        if not taken:
            threading.Event().wait(min(timeout, 0.02))
        return taken

    def __enter__(self) -> "Control":
        self.thread.start()
        return self

    def __exit__(self, *exc: object) -> None:
        self.loop.stop()
        self.thread.join(timeout=10)
        assert not self.thread.is_alive()


def test_an_assigned_order_starts_from_its_command_without_a_full_re_read() -> None:
    store = CountingStore()

    with Control(store) as control:
        assert store.synced.wait(5)  # the loop's first full sync, before the assignment
        store.orders = [order()]
        control.queue.append(ASSIGNED)
        assert control.published.wait(5)

    assert control.sent == ["TO-7"]
    assert store.full_reads == 1
    assert store.named_reads == [[7]]
    assert control.controller.counters["orders_read_on_command"] == 1


@dataclass
class SlowFlushStore(CountingStore):
    """A flush that lasts until `release` is set (or 5 s)."""

    flushing: threading.Event = field(default_factory=threading.Event)
    release: threading.Event = field(default_factory=threading.Event)
    released_in_flush: bool = False

    def flush(self, batch: FlushBatch) -> dict[tuple[str, str], int]:
        self.flushing.set()
        self.released_in_flush = self.release.wait(5)
        return super().flush(batch)


def test_an_assigned_order_does_not_wait_for_the_main_threads_periodic_work() -> None:
    store = SlowFlushStore()
    control = Control(store)
    store.release = control.published  # the flush ends once the order went out

    with control:
        assert store.flushing.wait(5)  # the main thread is in its first flush
        store.orders = [order()]
        control.queue.append(ASSIGNED)
        assert control.published.wait(5)

    assert store.released_in_flush  # the order went out while the flush still ran
    assert control.sent == ["TO-7"]


def test_other_commands_still_make_the_full_sync_due_at_once() -> None:
    store = CountingStore()

    with Control(store) as control:
        assert store.synced.wait(5)
        store.synced.clear()
        store.orders = [order()]
        control.queue.append({"kind": "order.cancel", "order": 3})
        assert store.synced.wait(5)
        assert control.published.wait(5)

    assert store.full_reads == 2  # the first round, and the one the command made due
    assert store.named_reads == []
    assert control.sent == ["TO-7"]


def test_syncs_between_full_reads_work_on_the_last_read_and_a_command_reads_again() -> None:
    store = CountingStore(orders=[order()])
    control = Control(store, QUIET | {"SYNC_INTERVAL": 0.01, "ORDER_READ_INTERVAL": 3600.0})
    synced: list[list[int]] = []
    sync = control.controller.sync

    def counted(orders: list[ActiveOrder], **kwargs: Any) -> None:
        synced.append([o.transport_order_id for o in orders])
        sync(orders, **kwargs)

    control.controller.sync = counted  # type: ignore[method-assign]

    with control:
        assert control.published.wait(5)  # the order of the first read went out
        deadline = time.monotonic() + 5
        while len(synced) < 5 and time.monotonic() < deadline:
            time.sleep(0.01)
        reads_before_command = store.full_reads
        store.synced.clear()
        control.queue.append({"kind": "order.cancel", "order": 7})
        assert store.synced.wait(5)

    assert len(synced) >= 5
    assert all(ids == [7] for ids in synced)  # the syncs in between had the last read's list
    assert reads_before_command == 1
    assert store.full_reads == 2  # the command made the next sync read again


def test_a_store_without_named_reads_falls_back_to_the_full_sync() -> None:
    store = FakeStore()

    with Control(store) as control:
        threading.Event().wait(0.2)  # the first full sync found nothing
        store.orders = [order()]
        control.queue.append(ASSIGNED)
        assert control.published.wait(5)

    assert control.sent == ["TO-7"]


class NamedReadDownStore(CountingStore):
    def assigned_orders(self, **named: list[int]) -> list[ActiveOrder]:
        raise ConnectionError("database is down")


def test_when_the_named_read_fails_the_full_sync_starts_the_order_at_once() -> None:
    store = NamedReadDownStore()

    with Control(store) as control:
        assert store.synced.wait(5)
        store.orders = [order()]
        control.queue.append(ASSIGNED)
        assert control.published.wait(5)

    assert control.sent == ["TO-7"]
    assert store.full_reads == 2  # not the periodic one (an hour away here)


def test_an_order_started_during_a_full_read_is_still_extended_after_that_reads_sync() -> None:
    """The command thread may start an order while the main thread reads the active orders
    from before its assignment: the sync of that read must not forget the order, or its base
    could not grow until the next one."""
    sent: list[dict[str, Any]] = []
    controller = Controller(
        store=FakeStore(),
        interface_name="uagv",
        publish=lambda t, payload, qos: sent.append(json.loads(payload)),
        base_ahead=1,
    )
    controller.load()
    controller.handle_message(topic(), state(last_node="a"))
    read_at = time.monotonic()  # the full read begins, without order 7 ...

    controller.start_orders([order()])  # ... which the command thread starts meanwhile
    controller.sync([], read_at=read_at)
    controller.handle_message(  # the vehicle took the order, then passed b
        topic(), state(header_id=2, order_id="TO-7", nodes=("b",), horizon=("c", "d"))
    )
    controller.handle_message(
        topic(), state(header_id=3, order_id="TO-7", last_node="b", horizon=("c", "d"))
    )

    updates = [m["orderUpdateId"] for m in sent if "nodes" in m]
    assert updates == [0, 1]  # the start, and the base extended past b


def test_which_commands_name_the_orders_to_start() -> None:
    commands = [
        {"kind": "order.assigned", "orders": [4, 5]},
        {"kind": "order.assigned", "charge_session": 2},
        {"kind": "order.cancel", "order": 4},
        {"kind": "order.assigned", "service_move": 9},
        {"kind": "order.assigned", "order": 3},  # no id it knows: for the full sync
        {"kind": "order.assigned", "orders": ["4", True]},
    ]

    assert assigned_jobs(commands) == {"orders": [4, 5], "charge_sessions": [2], "moves": [9]}
    assert [names_assigned(c) for c in commands] == [True, True, False, True, False, False]
