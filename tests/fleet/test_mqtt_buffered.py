"""The buffered paho client (`fleet.mqtt.BufferedClient`) that control reads the fleet with.

Its socket wrapper is checked on a real socket pair; the client itself over the real
Mosquitto: every message arrives once, whole and in order, whatever the sizes (a chunk holds
hundreds of packets; one payload is larger than a chunk), and a handler that publishes on
every message still gets its publishes out during a burst.
"""

import socket
import threading
import time
import uuid

import paho.mqtt.client as mqtt
import pytest
from django.conf import settings
from paho.mqtt.enums import CallbackAPIVersion

from fleet.mqtt import READ_CHUNK, ReceivedMessage, _BufferedSocket, make_client


def test_the_wrapper_hands_out_what_one_read_got_in_the_sizes_asked_for() -> None:
    left, right = socket.socketpair()
    try:
        right.setblocking(False)
        wrapped = _BufferedSocket(right)
        left.sendall(b"\x30\x05hello\x30\x02hi")
        time.sleep(0.05)
        assert wrapped.recv(1) == b"\x30"
        assert wrapped.pending() == 10  # one recv took all of it; paho's loop sees it buffered
        assert wrapped.recv(1) == b"\x05"
        assert wrapped.recv(5) == b"hello"
        assert wrapped.recv(100) == b"\x30\x02hi"  # asked for more: gets what is left
        assert wrapped.pending() == 0
        with pytest.raises(BlockingIOError):
            wrapped.recv(1)  # nothing buffered, nothing in the socket: paho's MQTT_ERR_AGAIN
        left.close()
        assert wrapped.recv(1) == b""  # the peer closed: paho's connection lost
    finally:
        left.close()
        right.close()


def _broker() -> tuple[str, int]:
    url = settings.MQTT_URL
    if settings.SERVICES.get("MQTT_URL", "").startswith("embedded"):
        pytest.skip("needs a broker (Mosquitto)")
    _, address = make_client(url, client_id_prefix="probe")
    return address.host, address.port


def _plain_client(host: str, port: int) -> mqtt.Client:
    client = mqtt.Client(callback_api_version=CallbackAPIVersion.VERSION2)
    client.connect(host, port)
    client.loop_start()
    return client


def test_every_message_arrives_whole_and_in_order_through_the_buffered_client() -> None:
    host, port = _broker()
    topic = f"buffered/{uuid.uuid4().hex[:8]}"
    sizes = [10, 1_500, 70, 200_000, 3] * 400 + [READ_CHUNK * 2 + 17]
    sent = [bytes([i % 251]) * size for i, size in enumerate(sizes)]
    received: list[bytes] = []
    done = threading.Event()
    subscribed = threading.Event()

    client, _ = make_client(settings.MQTT_URL, client_id_prefix="buffered-test")

    def on_message(client: mqtt.Client, userdata: object, message: mqtt.MQTTMessage) -> None:
        received.append(bytes(message.payload))
        if len(received) == len(sent):
            done.set()

    client.on_message = on_message
    client.on_subscribe = lambda *args: subscribed.set()
    client.connect(host, port)
    client.subscribe(topic, qos=1)
    client.loop_start()
    sender = _plain_client(host, port)
    try:
        assert subscribed.wait(5)
        for index, payload in enumerate(sent):
            sender.publish(topic, payload, qos=1)
            # Mosquitto queues at most 1,000 QoS 1 messages for a subscriber that lags and
            # drops the rest: keep the burst (hundreds of packets a read) under that.
            deadline = time.monotonic() + 30
            while index - len(received) > 500 and time.monotonic() < deadline:
                time.sleep(0.005)
        assert done.wait(60), f"{len(received)} of {len(sent)} arrived"
        assert received == sent
    finally:
        for each in (client, sender):
            each.disconnect()
            each.loop_stop()


def test_a_handler_that_publishes_on_every_message_gets_all_its_publishes_out() -> None:
    host, port = _broker()
    prefix = f"buffered/{uuid.uuid4().hex[:8]}"
    count = 3_000
    replies: list[bytes] = []
    all_replied = threading.Event()
    ready = threading.Event()

    client, _ = make_client(settings.MQTT_URL, client_id_prefix="buffered-echo")

    def echo(c: mqtt.Client, userdata: object, message: mqtt.MQTTMessage) -> None:
        c.publish(f"{prefix}/out", message.payload, qos=0)

    client.on_message = echo
    client.on_subscribe = lambda *args: ready.set()
    client.connect(host, port)
    client.subscribe(f"{prefix}/in", qos=0)
    client.loop_start()

    listener = _plain_client(host, port)
    heard = threading.Event()

    def on_reply(c: mqtt.Client, userdata: object, message: mqtt.MQTTMessage) -> None:
        replies.append(bytes(message.payload))
        if len(replies) == count:
            all_replied.set()

    listener.on_message = on_reply
    listener.on_subscribe = lambda *args: heard.set()
    listener.subscribe(f"{prefix}/out", qos=0)
    sender = _plain_client(host, port)
    try:
        assert ready.wait(5)
        assert heard.wait(5)
        for i in range(count):
            sender.publish(f"{prefix}/in", str(i).encode(), qos=0)
        assert all_replied.wait(30), f"{len(replies)} of {count} replies"
        assert replies == [str(i).encode() for i in range(count)]
    finally:
        for each in (client, listener, sender):
            each.disconnect()
            each.loop_stop()


def test_the_qos0_fast_path_keeps_paho_s_message_and_survives_a_failing_handler(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    host, port = _broker()
    general: list[int] = []  # publishes that went paho's general way
    paho_handle = mqtt.Client._handle_publish

    def counted(self: mqtt.Client) -> object:
        general.append(1)
        return paho_handle(self)

    monkeypatch.setattr(mqtt.Client, "_handle_publish", counted)
    topic = f"buffered/{uuid.uuid4().hex[:8]}/retained"
    sender = _plain_client(host, port)
    sender.publish(topic, b"kept", qos=0, retain=True).wait_for_publish(5)
    seen: list[tuple[str, bytes, bool, int]] = []
    second = threading.Event()
    client, _ = make_client(settings.MQTT_URL, client_id_prefix="buffered-fast")

    def on_message(c: mqtt.Client, userdata: object, message: mqtt.MQTTMessage) -> None:
        seen.append((message.topic, bytes(message.payload), message.retain, message.qos))
        if len(seen) == 1:
            raise RuntimeError("a handler bug")  # suppressed (make_client): the loop goes on
        second.set()

    client.on_message = on_message
    client.connect(host, port)
    client.subscribe(topic, qos=0)
    client.loop_start()
    try:
        deadline = time.monotonic() + 5
        while not seen and time.monotonic() < deadline:
            time.sleep(0.01)
        sender.publish(topic, b"live", qos=0)
        assert second.wait(5)
        assert seen == [(topic, b"kept", True, 0), (topic, b"live", False, 0)]
        assert general == []
    finally:
        sender.publish(topic, b"", qos=0, retain=True)  # clear the retained message
        for each in (client, sender):
            each.disconnect()
            each.loop_stop()


def _publish(topic: bytes, payload: bytes, *, qos: int = 0, retain: bool = False) -> bytes:
    """One MQTT 3.1.1 PUBLISH packet, as the broker writes it."""
    header = 0x30 | (qos << 1) | int(retain)
    body = len(topic).to_bytes(2, "big") + topic + (b"\x00\x07" if qos else b"") + payload
    length, encoded = len(body), bytearray()
    while True:
        byte, length = length % 128, length // 128
        encoded.append(byte | (0x80 if length else 0))
        if not length:
            return bytes([header]) + bytes(encoded) + body


def test_publishes_whole_in_the_buffer_are_read_from_it_and_the_rest_the_paho_way(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    general: list[int] = []  # packets that went through paho's own reading
    paho_read = mqtt.Client._packet_read

    def counted(self: mqtt.Client) -> object:
        general.append(1)
        return paho_read(self)

    monkeypatch.setattr(mqtt.Client, "_packet_read", counted)
    client, _ = make_client("mqtt://127.0.0.1:1", client_id_prefix="buffer-parse")
    seen: list[tuple[str, bytes, bool]] = []

    def on_message(c: mqtt.Client, userdata: object, message: mqtt.MQTTMessage) -> None:
        seen.append((message.topic, bytes(message.payload), message.retain))
        if message.payload == b"boom":
            raise RuntimeError("a handler bug")  # suppressed: the next packets still come

    client.on_message = on_message
    left, right = socket.socketpair()
    try:
        right.setblocking(False)
        client._sock = _BufferedSocket(right)
        big = b"x" * 300  # a two-byte remaining length
        huge = b"y" * 20_000  # three bytes
        tail = _publish(b"v/split", b"second half")
        left.sendall(
            _publish(b"v/a", b"one")
            + _publish(b"v/b", big, retain=True)
            + _publish(b"v/h", huge)
            + _publish(b"v/c", b"boom")
            + b"\xd0\x00"  # PINGRESP: paho's
            + _publish(b"v/d", b"after ping")
            + tail[:6]
        )
        time.sleep(0.05)
        while client.loop_read() == mqtt.MQTT_ERR_SUCCESS and client._sock.buffered():
            pass
        assert seen == [
            ("v/a", b"one", False),
            ("v/b", big, True),
            ("v/h", huge, False),
            ("v/c", b"boom", False),
            ("v/d", b"after ping", False),
        ]
        # paho read only the PINGRESP and the part of the split packet; the publishes whole
        # in the buffer did not go through it
        assert len(general) == 2
        left.sendall(tail[6:] + _publish(b"v/e", b"last"))
        time.sleep(0.05)
        client.loop_read()
        assert seen[5:] == [("v/split", b"second half", False), ("v/e", b"last", False)]
    finally:
        client._sock = None
        left.close()
        right.close()


def test_a_read_stops_at_a_publish_from_the_handler_and_writes_it_at_once() -> None:
    client, _ = make_client("mqtt://127.0.0.1:1", client_id_prefix="buffer-write")
    seen: list[str] = []

    def on_message(c: mqtt.Client, userdata: object, message: mqtt.MQTTMessage) -> None:
        seen.append(message.topic)
        if message.topic == "v/b":
            c.publish("v/b/order", b"update", qos=0)  # an order update a state caused

    client.on_message = on_message
    client._state = mqtt._ConnectionState.MQTT_CS_CONNECTED  # as after CONNACK
    left, right = socket.socketpair()
    try:
        right.setblocking(False)
        client._sock = _BufferedSocket(right)
        left.sendall(b"".join(_publish(t, b"state") for t in (b"v/a", b"v/b", b"v/c")))
        time.sleep(0.05)
        assert client.loop_read() == mqtt.MQTT_ERR_SUCCESS
        assert seen == ["v/a", "v/b"]  # v/c waits for the next read
        left.settimeout(1)
        assert left.recv(100) == _publish(b"v/b/order", b"update")
        client.loop_read()
        assert seen == ["v/a", "v/b", "v/c"]
    finally:
        client._sock = None
        left.close()
        right.close()


def _reads_for_a_steady_stream(monkeypatch: pytest.MonkeyPatch, read_pause: float) -> int:
    """Socket reads the buffered client makes for 200 messages sent 5 ms apart (all arrive,
    in order)."""
    host, port = _broker()
    topic = f"buffered/{uuid.uuid4().hex[:8]}"
    reads = []
    fill = _BufferedSocket.fill

    def counted(sock: _BufferedSocket) -> int:
        reads.append(1)
        return fill(sock)

    received: list[bytes] = []
    done, subscribed = threading.Event(), threading.Event()
    client, _ = make_client(settings.MQTT_URL, client_id_prefix="paced", read_pause=read_pause)

    def on_message(client: mqtt.Client, userdata: object, message: mqtt.MQTTMessage) -> None:
        received.append(bytes(message.payload))
        if len(received) == 200:
            done.set()

    client.on_message = on_message
    client.on_subscribe = lambda *args: subscribed.set()
    client.connect(host, port)
    client.subscribe(topic, qos=0)
    client.loop_start()
    sender = _plain_client(host, port)
    try:
        assert subscribed.wait(5)
        monkeypatch.setattr(_BufferedSocket, "fill", counted)
        for i in range(200):
            sender.publish(topic, str(i).encode(), qos=0)
            time.sleep(0.005)
        assert done.wait(10), f"{len(received)} of 200 arrived"
        assert received == [str(i).encode() for i in range(200)]
    finally:
        monkeypatch.setattr(_BufferedSocket, "fill", fill)
        for each in (client, sender):
            each.disconnect()
            each.loop_stop()
    return len(reads)


def test_a_read_pause_gathers_a_steady_stream_into_fewer_reads(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    at_once = _reads_for_a_steady_stream(monkeypatch, 0.0)
    paced = _reads_for_a_steady_stream(monkeypatch, 0.05)
    # 200 messages over at least a second: about one read per message, against one per 50 ms
    assert paced <= 40
    assert paced * 2 < at_once


def test_a_received_message_has_every_field_paho_s_own_message_has() -> None:
    ours = ReceivedMessage(b"uagv/v2/M/S/state", b"{}", 0x30 | 0x08 | 0x01)
    paho = mqtt.MQTTMessage(topic=b"uagv/v2/M/S/state")
    paho.payload, paho.retain, paho.dup = b"{}", True, True
    assert isinstance(ours, mqtt.MQTTMessage)
    for name in mqtt.MQTTMessage.__slots__:
        if name not in ("timestamp", "info"):
            assert getattr(ours, name) == getattr(paho, name), name
    assert ours.topic == "uagv/v2/M/S/state"
    assert ours.timestamp > 0
    assert ours.info.mid == 0
    plain = ReceivedMessage(b"t", b"", 0x30)
    assert (plain.retain, plain.dup) == (False, False)
