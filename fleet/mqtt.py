"""MQTT client factory: one place that turns MQTT_URL into a configured paho client."""

import ssl
import time
import uuid
from dataclasses import dataclass
from typing import Any
from urllib.parse import unquote, urlsplit

import paho.mqtt.client as mqtt
from paho.mqtt.enums import CallbackAPIVersion, MQTTErrorCode

# Bytes asked of the kernel per read: a few hundred state messages of a busy fleet.
READ_CHUNK = 256 * 1024
# Packets handled per read event before paho's loop gets its turn (writes, keepalive).
PACKETS_PER_READ = 64


@dataclass(frozen=True)
class BrokerAddress:
    """Where the broker is and how to log in, parsed from an `mqtt://` or `mqtts://` URL."""

    host: str
    port: int
    tls: bool = False
    username: str | None = None
    password: str | None = None

    @classmethod
    def from_url(cls, url: str) -> "BrokerAddress":
        parts = urlsplit(url)
        if parts.scheme not in {"mqtt", "mqtts", "tcp", "ssl"}:
            raise ValueError(f"MQTT URL must start with mqtt:// or mqtts://, got {url!r}")
        tls = parts.scheme in {"mqtts", "ssl"}
        return cls(
            host=parts.hostname or "127.0.0.1",
            port=parts.port or (8883 if tls else 1883),
            tls=tls,
            username=unquote(parts.username) if parts.username else None,
            password=unquote(parts.password) if parts.password else None,
        )


class _BufferedSocket:
    """The broker socket, read in large chunks and handed to paho a few bytes at a time.

    paho reads each packet with at least three `recv` calls (the command byte, each byte of
    the remaining length, the rest) and one `select` in between packets: at 3,000 messages a
    second that was a good part of control's paho thread. `pending()` is paho's own test
    for bytes buffered above the socket (it asks it of TLS sockets), so paho's loop does not
    wait in `select` while bytes are buffered here.
    """

    __slots__ = ("_sock", "_buffer", "_pos")

    def __init__(self, sock: Any) -> None:
        self._sock = sock
        self._buffer = b""
        self._pos = 0

    def recv(self, size: int) -> bytes:
        if self._pos >= len(self._buffer):
            data: bytes = self._sock.recv(max(size, READ_CHUNK))  # may raise BlockingIOError
            if len(data) <= size:  # also b"": the broker closed the connection
                return data
            self._buffer, self._pos = data, 0
        start = self._pos
        self._pos = min(start + size, len(self._buffer))
        return self._buffer[start : self._pos]

    def fill(self) -> int:
        """Read what the socket has (up to a chunk) into the empty buffer; the bytes read, 0
        if the broker closed the connection. Raises BlockingIOError when nothing is there."""
        data: bytes = self._sock.recv(READ_CHUNK)
        self._buffer, self._pos = data, 0
        return len(data)

    def buffered(self) -> int:
        """Bytes read from the socket that paho has not taken yet."""
        return len(self._buffer) - self._pos

    def pending(self) -> int:
        inner = self._sock.pending() if hasattr(self._sock, "pending") else 0
        return self.buffered() + inner

    def send(self, data: bytes | bytearray) -> int:
        sent: int = self._sock.send(data)
        return sent

    def fileno(self) -> int:
        fileno: int = self._sock.fileno()
        return fileno

    def close(self) -> None:
        self._sock.close()

    def setblocking(self, flag: bool) -> None:
        self._sock.setblocking(flag)

    def __getattr__(self, name: str) -> Any:
        return getattr(self._sock, name)


class ReceivedMessage(mqtt.MQTTMessage):
    """A received QoS 0 publish, as `on_message` gets it: paho's `MQTTMessage` without building
    an `MQTTMessageInfo` (a lock and a condition, 3 µs of 3.5) that only sent messages use."""

    __slots__ = ()

    _NO_INFO = mqtt.MQTTMessageInfo(0)  # shared: nobody waits on a received message

    def __init__(self, topic: bytes, payload: bytes, header: int) -> None:
        # paho's __init__ is skipped on purpose (it builds the MQTTMessageInfo); every slot
        # it sets is set here.
        self.timestamp = mqtt.time_func()
        self.state = mqtt.mqtt_ms_invalid
        self.dup = bool(header & 0x08)
        self.mid = 0
        self._topic = topic
        self.payload = payload
        self.qos = 0
        self.retain = bool(header & 0x01)
        self.info = self._NO_INFO
        self.properties = None


class BufferedClient(mqtt.Client):
    """A paho client that reads its socket in chunks and handles a burst of packets per read.

    Same behaviour as `mqtt.Client` (the tests run control's suites over it); only the
    reading is cheaper. Each read event handles at most `PACKETS_PER_READ` packets and
    stops early when something waits to be written, so publishes and keepalives are not
    held behind a burst of incoming messages.
    """

    _filtered = False  # a per-topic callback was added: paho's own dispatch is needed
    # Seconds between two reads of the socket at least (0: read as soon as bytes arrive).
    # At thousands of messages a second each read brought one or two; waiting a few
    # milliseconds lets a read bring a dozen, for one select and one recv instead of twelve.
    read_pause = 0.0
    _last_fill = float("-inf")  # monotonic

    def _create_socket(self) -> Any:
        return _BufferedSocket(super()._create_socket())

    def message_callback_add(self, sub: str, callback: Any) -> None:
        self._filtered = True
        super().message_callback_add(sub, callback)

    def _handle_publish(self) -> MQTTErrorCode:
        """A QoS 0 publish of MQTT 3.1.1 straight to `on_message` (the fleet's states and
        visualizations); everything else (QoS 1 and 2, MQTT 5, per-topic callbacks, a
        malformed packet) as paho does it. paho's general path decodes, logs and matches the
        topic against its callback tree for every message: a fifth of control's paho time."""
        header, data = self._in_packet["command"], self._in_packet["packet"]
        size = int.from_bytes(data[:2], "big")
        if header & 0x06 or self._protocol == mqtt.MQTTv5 or self._filtered or size == 0:
            return super()._handle_publish()
        if len(data) < 2 + size:
            return super()._handle_publish()  # paho raises MalformedPacket
        message = ReceivedMessage(bytes(data[2 : 2 + size]), bytes(data[2 + size :]), header)
        on_message = self.on_message
        if on_message is not None:
            with self._in_callback_mutex:
                self._deliver(on_message, message)
        return MQTTErrorCode.MQTT_ERR_SUCCESS

    def loop_read(self, max_packets: int = 1) -> MQTTErrorCode:
        """Handle up to `PACKETS_PER_READ` packets: whole QoS 0 publishes straight from the
        read buffer (filled here when empty), anything else the paho way; then write what
        the handlers published."""
        sock = self._sock
        if not isinstance(sock, _BufferedSocket):
            return super().loop_read(max_packets)
        rc, handled = MQTTErrorCode.MQTT_ERR_SUCCESS, 0
        if not sock.buffered() and self._in_packet["command"] == 0:
            if self.read_pause > 0:
                self._pause_before_reading()
            try:
                if not sock.fill():
                    return super().loop_read(max_packets)  # closed: paho reports the loss
            except BlockingIOError:
                return rc
            except OSError:
                return super().loop_read(max_packets)  # paho logs and reports it
        while handled < PACKETS_PER_READ:
            if sock.buffered() and self._in_packet["command"] == 0:
                direct = self._publishes_from_buffer(sock, PACKETS_PER_READ - handled)
                handled += direct
                if direct and (not sock.buffered() or self.want_write()):
                    break
                if handled >= PACKETS_PER_READ:
                    break
            left = sock.buffered()
            rc = super().loop_read(max_packets)
            handled += 1
            if rc != MQTTErrorCode.MQTT_ERR_SUCCESS or self._sock is not sock:
                break
            if not sock.buffered() or sock.buffered() == left or self.want_write():
                break  # drained, a partial packet (the rest is not here yet), or a write waits
        if rc == MQTTErrorCode.MQTT_ERR_SUCCESS and self._sock is sock and self.want_write():
            # What the handlers published (order updates) goes out now: paho's loop would
            # write it only after its next select and the next read.
            rc = self.loop_write()
        return rc

    def _pause_before_reading(self) -> None:
        """Sleep until `read_pause` s have passed since the last read: only when messages
        come faster than that (a quiet link reads at once)."""
        now = time.monotonic()
        wait = self._last_fill + self.read_pause - now
        if wait > 0:
            time.sleep(wait)
            now += wait
        self._last_fill = now

    def _publishes_from_buffer(self, sock: _BufferedSocket, limit: int) -> int:
        """Hand the whole QoS 0 publishes at the head of the read buffer to `on_message`.

        paho reads each packet with four `recv` calls, a dict of reading state and a
        dispatch on the command: for a fleet's states and visualizations that was a good
        part of control's paho thread. Stops after a publish that made something to write
        (an order update waits for no further message), and at anything else (another
        packet type, QoS 1 or 2, a packet not yet whole, a malformed topic length), which
        paho then reads itself; never with MQTT 5 or per-topic callbacks."""
        if self._protocol == mqtt.MQTTv5 or self._filtered:
            return 0
        buffer, pos, end = sock._buffer, sock._pos, len(sock._buffer)
        handled = 0
        on_message = self.on_message
        with self._in_callback_mutex:
            while handled < limit and pos + 4 <= end:
                header = buffer[pos]
                if header & 0xF6 != 0x30:  # PUBLISH with QoS 0 (dup and retain may be set)
                    break
                first = buffer[pos + 1]  # the remaining length: one or two bytes for a state
                if first < 0x80:
                    length, start = first, pos + 2
                elif buffer[pos + 2] < 0x80:  # pos + 4 <= end: this byte is there
                    length, start = (first & 0x7F) | (buffer[pos + 2] << 7), pos + 3
                else:
                    length, start = _remaining_length(buffer, pos + 1, end)
                if length < 0 or start + length > end:
                    break  # not whole yet, or a length paho should judge
                size = (buffer[start] << 8) | buffer[start + 1]
                if size == 0 or 2 + size > length:
                    break  # paho raises MalformedPacket
                message = ReceivedMessage(
                    buffer[start + 2 : start + 2 + size],
                    buffer[start + 2 + size : start + length],
                    header,
                )
                pos = sock._pos = start + length
                handled += 1
                if on_message is not None:
                    self._deliver(on_message, message)
                if self._out_packet:
                    break  # the handler published: loop_read writes it before reading on
        if handled:
            with self._msgtime_mutex:
                self._last_bytes_received = mqtt.time_func()
        return handled

    def _deliver(self, on_message: Any, message: mqtt.MQTTMessage) -> None:
        try:
            on_message(self, self._userdata, message)
        except Exception as err:
            self._easy_log(mqtt.MQTT_LOG_ERR, "Caught exception in on_message: %s", err)
            if not self.suppress_exceptions:
                raise


def _remaining_length(buffer: bytes, pos: int, end: int) -> tuple[int, int]:
    """MQTT's variable-length "remaining length" at `pos`: (length, where the rest starts),
    or (-1, pos) when it is not all in the buffer or longer than the four bytes allowed."""
    length, shift = 0, 0
    for index in range(pos, min(pos + 4, end)):
        byte = buffer[index]
        length |= (byte & 0x7F) << shift
        if not byte & 0x80:
            return length, index + 1
        shift += 7
    return -1, pos


def make_client(
    url: str, *, client_id_prefix: str, read_pause: float = 0.0
) -> tuple[mqtt.Client, BrokerAddress]:
    """A paho client (MQTT 3.1.1, callback API v2) for the broker at `url`, not yet connected
    (`read_pause`: see `BufferedClient.read_pause`).

    Callback exceptions are suppressed so that one bad message can never stop paho's network
    loop; handlers still catch and log their own errors.
    """
    address = BrokerAddress.from_url(url)
    client = BufferedClient(
        callback_api_version=CallbackAPIVersion.VERSION2,
        client_id=f"{client_id_prefix}-{uuid.uuid4().hex[:8]}",
        protocol=mqtt.MQTTv311,
        clean_session=True,
    )
    client.suppress_exceptions = True
    client.read_pause = read_pause
    if address.username:
        client.username_pw_set(address.username, address.password)
    if address.tls:
        client.tls_set(cert_reqs=ssl.CERT_REQUIRED)
    client.reconnect_delay_set(min_delay=1, max_delay=10)
    return client, address
