"""The vehicle page's message log in `control`: latest per topic, a bounded ring, watches that
expire, and the hooks where control decodes and publishes."""

import json

from control.controller import Controller
from control.message_log import IN, OUT, MessageLog
from tests.control.fakes import FakeStore, state, topic

KEY = ("sim", "AGV-1")


class Clock:
    def __init__(self) -> None:
        self.now = 100.0

    def __call__(self) -> float:
        return self.now


def test_keeps_the_latest_message_per_topic_and_a_bounded_ring() -> None:
    log = MessageLog(ring_size=3)

    for header_id in range(5):
        log.record(KEY, IN, "state", f'{{"headerId": {header_id}}}'.encode())
    log.record(KEY, OUT, "order", b'{"orderId": "o-1"}')

    latest = log.latest(KEY)
    assert json.loads(latest["state"].payload)["headerId"] == 4
    assert latest["order"].direction == OUT
    recent = log.recent(KEY)
    assert [m.topic for m in recent] == ["state", "state", "order"]
    assert [m.seq for m in recent] == sorted(m.seq for m in recent)
    assert log.latest(("sim", "AGV-2")) == {}


def test_only_watched_vehicles_are_collected_and_only_what_is_new() -> None:
    clock = Clock()
    log = MessageLog(clock=clock)
    log.record(KEY, IN, "state", b'{"headerId": 1}')
    log.record(("sim", "AGV-2"), IN, "state", b'{"headerId": 1}')
    assert log.collect() == []  # nobody watches

    log.watch(KEY, seconds=30, full=True)
    first = log.collect()
    log.record(KEY, OUT, "instantActions", b'{"actions": []}')
    second = log.collect()
    third = log.collect()

    assert [b.key for b in first] == [KEY]
    assert first[0].latest is not None
    assert set(first[0].latest) == {"state"}
    assert [m["topic"] for m in first[0].messages] == ["state"]
    assert second[0].latest is None  # only a join resends the latest of every topic
    assert [(m["direction"], m["topic"]) for m in second[0].messages] == [(OUT, "instantActions")]
    assert second[0].messages[0]["json"] == '{"actions": []}'
    assert third == []  # nothing new, nothing sent


def test_visualizations_fill_the_ring_only_while_watched_and_orders_outlive_the_ring() -> None:
    log = MessageLog(ring_size=3)
    log.record(KEY, OUT, "order", b'{"orderUpdateId": 0}')
    log.record(KEY, OUT, "order", b'{"orderUpdateId": 1}')
    for header_id in range(5):
        log.record(KEY, IN, "visualization", f'{{"headerId": {header_id}}}'.encode())
        log.record(KEY, IN, "state", f'{{"headerId": {header_id}}}'.encode())

    assert [m.topic for m in log.recent(KEY)] == ["state"] * 3
    assert json.loads(log.latest(KEY)["visualization"].payload)["headerId"] == 4

    log.watch(KEY, full=True)
    log.record(KEY, IN, "visualization", b'{"headerId": 5}')
    joined = log.collect()[0]

    topics = [(m["topic"], json.loads(m["json"])) for m in joined.messages]
    assert topics[:2] == [("order", {"orderUpdateId": 0}), ("order", {"orderUpdateId": 1})]
    assert topics[-1] == ("visualization", {"headerId": 5})
    assert [m["seq"] for m in joined.messages] == sorted(m["seq"] for m in joined.messages)


def test_a_watch_expires_unless_renewed() -> None:
    clock = Clock()
    log = MessageLog(clock=clock)
    log.watch(KEY, seconds=30)

    clock.now += 20
    log.watch(KEY, seconds=30)  # the page renews
    clock.now += 20
    assert log.watched() == [KEY]

    clock.now += 11
    assert log.watched() == []
    log.record(KEY, IN, "state", b"{}")
    assert log.collect() == []


def test_a_watch_cannot_be_pinned_for_long() -> None:
    clock = Clock()
    log = MessageLog(clock=clock)
    log.watch(KEY, seconds=1e9)

    clock.now += 151
    assert log.watched() == []


def test_controller_logs_what_it_decodes_and_publishes_and_streams_watched_vehicles() -> None:
    published: list[tuple[str, bytes]] = []
    controller = Controller(
        store=FakeStore(),
        interface_name="uagv",
        publish=lambda t, p, q: published.append((t, p)),
    )
    controller.load()
    controller.handle_message(topic(), state(header_id=1))
    controller.handle_message(topic(), b"{not json")
    controller.execute({"kind": "vehicle.pause", "vehicle": 1})

    controller.execute({"kind": "vehicle.watch", "vehicle": 1, "seconds": 30, "full": True})
    events = controller.collect_watched()

    assert len(events) == 1
    pk, event = events[0]
    assert pk == 1
    assert event["vehicle"]["serial"] == "AGV-1"
    incoming = [m for m in event["messages"] if m["direction"] == IN]
    assert [m["topic"] for m in incoming] == ["state", "state"]
    assert incoming[1]["note"]  # the undecodable one says why it was dropped
    outgoing = [m for m in event["messages"] if m["direction"] == OUT]
    assert len(outgoing) == len(published)  # factsheetRequest after the first state, pause
    sent = json.loads(event["latest"]["instantActions"]["json"])
    assert sent["actions"][0]["actionType"] == "startPause"
    assert event["latest"]["instantActions"]["json"] == published[-1][1].decode()


def test_controller_ignores_watches_of_unknown_vehicles_and_streams_nothing_unwatched() -> None:
    controller = Controller(store=FakeStore(), interface_name="uagv")
    controller.load()
    controller.handle_message(topic(), state(header_id=1))

    controller.execute({"kind": "vehicle.watch", "vehicle": 999, "full": True})

    assert controller.collect_watched() == []
    assert controller.counters["bad_commands"] == 0
