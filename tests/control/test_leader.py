"""Leadership of `control` (issue 11 item 3): one leader through a PostgreSQL advisory lock, a
fencing number per term, a local lease checked before every publish, and a frozen leader whose
session the server ends so that a standby can take over without two publishers."""

import json
import os
import random
import signal
import subprocess
import sys
import threading
import time
import uuid
from collections import Counter
from collections.abc import Iterator
from pathlib import Path

import paho.mqtt.client as mqtt
import pytest
from django.conf import settings
from django.db import connection
from paho.mqtt.enums import CallbackAPIVersion

from control.controller import Controller
from control.driver import OrderDriver
from control.leader import Leadership, LeaseTimes, conninfo_from_settings
from control.standby import fence_mqtt_writes
from fleet.mqtt import BrokerAddress, make_client
from tests.control.fakes import FakeStore, order, state, topic

pytestmark = pytest.mark.django_db(transaction=True)

FAST = LeaseTimes(renew_every=0.4, lease=1.5, server_timeout=2.0, guard=1.8, retry_every=0.1)
ROOT = Path(__file__).resolve().parents[2]


@pytest.fixture
def postgres() -> str:
    if connection.vendor != "postgresql":
        pytest.skip("advisory locks need PostgreSQL")
    return conninfo_from_settings(connection.settings_dict)


@pytest.fixture
def lock_key() -> int:
    return random.randint(1, 2**31 - 1)  # noqa: S311 (no crosstalk between test runs)


@pytest.fixture
def leaderships(postgres: str, lock_key: int) -> Iterator[list[Leadership]]:
    made: list[Leadership] = []
    yield made
    for leadership in made:
        leadership.stop()


def wait_for(condition, timeout: float = 10.0) -> None:  # type: ignore[no-untyped-def]
    deadline = time.monotonic() + timeout
    while not condition():
        assert time.monotonic() < deadline, "timed out"
        time.sleep(0.02)


def test_lease_times_must_keep_the_lease_shorter_than_takeover() -> None:
    with pytest.raises(ValueError, match="lease"):
        LeaseTimes(lease=3.0, guard=2.0)
    with pytest.raises(ValueError, match="lease"):
        LeaseTimes(lease=3.0, server_timeout=3.0)


def test_one_leader_publishes_only_after_the_guard_and_the_standby_waits(
    postgres: str, lock_key: int, leaderships: list[Leadership]
) -> None:
    first = Leadership(postgres, FAST, lock_key=lock_key)
    leaderships.append(first)
    first.start()
    wait_for(lambda: first.role == "leader")
    took = time.monotonic()
    assert not first.holds_lease()  # still in the guard time
    assert first.wait_until_leading(threading.Event())
    assert time.monotonic() - took >= FAST.guard - 0.1
    assert first.holds_lease()

    second = Leadership(postgres, FAST, lock_key=lock_key)
    leaderships.append(second)
    second.start()
    time.sleep(FAST.server_timeout)
    assert second.role == "standby"
    assert not second.holds_lease()
    assert second.database_ok
    wait_for(first.holds_lease, timeout=2)  # renewed all along (a loaded CI may lag)
    assert first.status()["role"] == "leader"
    assert first.status()["fencing"] == first.fencing


def test_the_standby_takes_over_with_a_higher_fencing_number_when_the_leader_stops(
    postgres: str, lock_key: int, leaderships: list[Leadership]
) -> None:
    first, second = (Leadership(postgres, FAST, lock_key=lock_key) for _ in range(2))
    leaderships.extend([first, second])
    first.start()
    assert first.wait_until_leading(threading.Event())
    second.start()
    old_fencing = first.fencing
    assert old_fencing is not None

    first.stop()
    stopped = time.monotonic()
    assert not first.holds_lease()
    assert second.wait_until_leading(threading.Event())
    assert time.monotonic() - stopped >= FAST.guard - 0.1
    assert second.fencing is not None
    assert second.fencing > old_fencing


def test_a_leader_whose_session_is_ended_steps_down_at_its_next_renewal(
    postgres: str, lock_key: int, leaderships: list[Leadership]
) -> None:
    leader = Leadership(postgres, FAST, lock_key=lock_key)
    leaderships.append(leader)
    leader.start()
    assert leader.wait_until_leading(threading.Event())
    with connection.cursor() as cursor:  # what a database restart does to the session
        cursor.execute(
            "SELECT pg_terminate_backend(pid) FROM pg_stat_activity"
            " WHERE application_name = 'fleet-control-leader' AND pid IN"
            " (SELECT pid FROM pg_locks WHERE locktype = 'advisory' AND objid = %s)",
            [lock_key],
        )
    wait_for(lambda: leader.lost.is_set(), timeout=FAST.renew_every + 2)
    assert not leader.holds_lease()
    assert leader.role == "standby"
    assert leader.wait_until_leading(threading.Event())  # the lock is free again: it leads anew


FROZEN_LEADER = """
import json, sys, time, threading
from control.leader import Leadership, LeaseTimes
times = LeaseTimes(renew_every=0.4, lease=1.5, server_timeout=2.0, guard=1.8, retry_every=0.1)
leadership = Leadership(sys.argv[1], times, lock_key=int(sys.argv[2]))
leadership.start()
leadership.wait_until_leading(threading.Event())
while True:  # what the publisher asks before each message
    print(json.dumps([time.time(), leadership.holds_lease(), leadership.role]), flush=True)
    time.sleep(0.02)
"""


# Rerun: SIGSTOP/SIGCONT and server timeouts timed against each other.
@pytest.mark.flaky(reruns=2, reruns_delay=5)
def test_a_frozen_leader_never_publishes_after_the_standby_took_over(
    postgres: str, lock_key: int, leaderships: list[Leadership], tmp_path: Path
) -> None:
    """SIGSTOP the leader: the server ends its idle-in-transaction session, the standby takes
    the lock, and after SIGCONT the old leader's lease is already expired: no overlap."""
    log = (tmp_path / "leader.log").open("w")
    frozen = subprocess.Popen(  # noqa: S603 (our interpreter)
        [sys.executable, "-c", FROZEN_LEADER, postgres, str(lock_key)],
        cwd=ROOT,
        stdout=log,
        stderr=subprocess.STDOUT,
        env={**os.environ, "PYTHONPATH": str(ROOT)},
    )

    def lines() -> list[list]:  # type: ignore[type-arg]
        text = (tmp_path / "leader.log").read_text()
        return [entry for line in text.splitlines() if (entry := _entry(line)) is not None]

    try:
        wait_for(lambda: any(ok for _, ok, _ in lines()), timeout=20)
        standby = Leadership(postgres, FAST, lock_key=lock_key)
        leaderships.append(standby)
        standby.start()
        time.sleep(0.5)
        assert standby.role == "standby"

        frozen.send_signal(signal.SIGSTOP)
        # The signal takes effect asynchronously: only what the leader printed after it really
        # stopped counts (a line stamped just after kill() may be from before the stop).
        wait_for(lambda: _process_state(frozen.pid) == "T", timeout=10)
        frozen_at = time.time()
        assert standby.wait_until_leading(threading.Event())
        took_over = time.time()
        assert took_over - frozen_at < FAST.server_timeout + FAST.retry_every + FAST.guard + 5
        time.sleep(1.0)
        frozen.send_signal(signal.SIGCONT)
        wait_for(lambda: lines()[-1][2] == "standby", timeout=10)
        woke = [entry for entry in lines() if entry[0] > frozen_at]
        assert woke, "the leader printed nothing after waking"
        assert not any(ok for _, ok, _ in woke)  # not one publish allowed after the freeze
        assert standby.holds_lease()
    finally:
        frozen.send_signal(signal.SIGCONT)
        frozen.kill()
        frozen.wait()
        log.close()


def _entry(line: str) -> list | None:  # type: ignore[type-arg]
    """One printed line of the leader, or None for a line caught half-written."""
    try:
        entry = json.loads(line)
    except ValueError:
        return None
    return entry if isinstance(entry, list) and len(entry) == 3 else None


def _process_state(pid: int) -> str:
    """The one-letter state of a process from /proc (T: stopped)."""
    stat = Path(f"/proc/{pid}/stat").read_text()
    return stat.rsplit(")", 1)[1].split()[0]


def test_the_publisher_sends_nothing_without_a_lease(monkeypatch: pytest.MonkeyPatch) -> None:
    sent: list[str] = []
    controller = Controller(
        store=FakeStore(), interface_name="uagv", publish=lambda t, p, q: sent.append(t)
    )
    controller.load()
    lease = {"valid": False}
    controller.publisher.may_publish = lambda: lease["valid"]
    controller.handle_message(topic(), state(last_node="a"))

    controller.sync([order()])
    assert not [t for t in sent if t.endswith("/order")]
    assert controller.counters["publish_fenced"] >= 1

    lease["valid"] = True  # the identical resend goes out once the lease runs again
    monkeypatch.setattr(OrderDriver, "RESEND_AFTER", 0.0)
    controller.sync([order()])
    assert [t for t in sent if t.endswith("/order")]


def test_messages_queued_in_paho_before_the_lease_ran_out_are_not_written() -> None:
    """The frozen-leader case at the socket: paho writes from its own thread, later than the
    publisher's check; what is still queued when the lease has run out is dropped."""
    url = settings.MQTT_URL
    if not url.startswith("mqtt://") or settings.MQTT_EMBEDDED:
        pytest.skip("needs Mosquitto")
    address = BrokerAddress.from_url(url)
    topic_name = f"leadertest/{uuid.uuid4().hex}/order"
    received: list[bytes] = []
    subscribed = threading.Event()
    sniffer = mqtt.Client(callback_api_version=CallbackAPIVersion.VERSION2)
    sniffer.on_message = lambda c, u, m: received.append(bytes(m.payload))
    sniffer.on_subscribe = lambda *args: subscribed.set()
    sniffer.connect(address.host, address.port)
    sniffer.subscribe(topic_name)
    sniffer.loop_start()
    client, _ = make_client(url, client_id_prefix="leader-test")
    counters: Counter[str] = Counter()
    lease = {"valid": False}
    fence_mqtt_writes(client, lambda: lease["valid"], counters)
    client.connect(address.host, address.port)
    client.loop_start()
    try:
        assert subscribed.wait(5)
        wait_for(client.is_connected, timeout=5)
        client.publish(topic_name, b"stale", qos=0)  # queued as if just before a freeze
        wait_for(lambda: counters["publish_fenced_in_paho"] == 1, timeout=5)
        lease["valid"] = True
        client.publish(topic_name, b"fresh", qos=0)
        wait_for(lambda: received, timeout=5)
        time.sleep(0.2)
        assert received == [b"fresh"]
    finally:
        client.loop_stop()
        client.disconnect()
        sniffer.loop_stop()
        sniffer.disconnect()
