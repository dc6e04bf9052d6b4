"""The generated Mosquitto configuration, checked against a real broker on a free port.

Denied publishes still get a success acknowledgement under MQTT 3.1.1, so every check observes
delivery: after the publishes that must not arrive, the same client publishes a message that must
arrive, and the check waits for that marker (a broker delivers one client's messages in order).
"""

import os
import shutil
import socket
import subprocess
import threading
import time
import uuid
from collections.abc import Iterator
from dataclasses import dataclass, field
from pathlib import Path

import paho.mqtt.client as mqtt
import pytest
from django.core.management import CommandError, call_command
from paho.mqtt.enums import CallbackAPIVersion

from robots import mosquitto
from robots.models import Vehicle
from robots.services import issue_mqtt_password, write_broker_files

pytestmark = [
    pytest.mark.django_db,
    pytest.mark.skipif(shutil.which("mosquitto") is None, reason="mosquitto is not installed"),
]

MASTER = ("fleet", "master-secret")
VEHICLES = [  # manufacturer, serial, protocol version
    ("Acme", "AGV-1", "2.0.0"),
    ("Acme", "AGV-2", "2.1.0"),
    ("Beta", "X-3", "3.0.0"),
]


def free_port() -> int:
    with socket.socket() as sock:
        sock.bind(("127.0.0.1", 0))
        return int(sock.getsockname()[1])


@dataclass
class Login:
    username: str
    password: str
    prefix: str = ""
    commands: tuple[str, ...] = ()


@dataclass
class Peer:
    """A connected client that records every message it receives."""

    client: mqtt.Client
    received: list[tuple[str, bytes]] = field(default_factory=list)
    arrived: threading.Condition = field(default_factory=threading.Condition)

    def saw(self, topic: str, payload: bytes) -> bool:
        return (topic, payload) in self.received

    def wait_for(self, topic: str, payload: bytes, timeout: float = 5.0) -> bool:
        with self.arrived:
            return self.arrived.wait_for(lambda: self.saw(topic, payload), timeout)


def connect(port: int, login: Login | None, protocol: int) -> tuple[Peer | None, object]:
    """Connect and return (peer, reason code); peer is None when the broker refused."""
    client = mqtt.Client(
        callback_api_version=CallbackAPIVersion.VERSION2,
        client_id=f"acl-{uuid.uuid4().hex[:10]}",
        protocol=protocol,
    )
    if login is not None:
        client.username_pw_set(login.username, login.password)
    peer = Peer(client)
    outcome: dict[str, object] = {}
    done = threading.Event()

    def on_connect(_c, _u, _f, reason_code, _p):  # type: ignore[no-untyped-def]
        outcome["rc"] = reason_code
        done.set()

    def on_message(_c, _u, message):  # type: ignore[no-untyped-def]
        with peer.arrived:
            peer.received.append((message.topic, message.payload))
            peer.arrived.notify_all()

    client.on_connect = on_connect
    client.on_message = on_message
    client.connect("127.0.0.1", port)
    client.loop_start()
    assert done.wait(5), "no CONNACK"
    rc = outcome["rc"]
    if getattr(rc, "is_failure", False):
        client.loop_stop()
        client.disconnect()
        return None, rc
    return peer, rc


def subscribe(peer: Peer, topic: str) -> None:
    done = threading.Event()
    peer.client.on_subscribe = lambda *_args: done.set()
    peer.client.subscribe(topic, qos=1)
    assert done.wait(5), f"no SUBACK for {topic}"


@pytest.fixture
def broker(tmp_path: Path) -> Iterator[tuple[int, Login, list[Login]]]:
    logins = []
    for manufacturer, serial, version in VEHICLES:
        vehicle = Vehicle.objects.create(
            manufacturer=manufacturer, serial_number=serial, protocol_version=version
        )
        username, password = issue_mqtt_password(vehicle=vehicle)
        major = mosquitto.major_version(version)
        logins.append(
            Login(
                username,
                password,
                prefix=f"uagv/{major}/{manufacturer}/{serial}",
                commands=mosquitto.master_to_vehicle_topics(major),
            )
        )
    port = free_port()
    # Mosquitto started by root drops to its own user, which cannot read pytest's private tmp.
    extra = ["user root"] if os.geteuid() == 0 else []
    files = write_broker_files(
        directory=tmp_path,
        master_username=MASTER[0],
        master_password=MASTER[1],
        listeners=mosquitto.Listeners(port=port, bind="127.0.0.1", extra=extra),
    )
    log = (tmp_path / "mosquitto.log").open("w")
    process = subprocess.Popen(["mosquitto", "-c", str(files.config)], stdout=log, stderr=log)
    deadline = time.monotonic() + 10
    while time.monotonic() < deadline:
        try:
            socket.create_connection(("127.0.0.1", port), 0.2).close()
            break
        except OSError:
            assert process.poll() is None, (tmp_path / "mosquitto.log").read_text()
            time.sleep(0.05)
    try:
        yield port, Login(*MASTER), logins
    finally:
        process.terminate()
        process.wait(5)
        log.close()


@pytest.mark.parametrize("protocol", [mqtt.MQTTv311, mqtt.MQTTv5], ids=["3.1.1", "5"])
def test_nothing_crosses_between_vehicles(broker, protocol) -> None:
    port, master_login, logins = broker
    checked = 0
    master, _ = connect(port, master_login, protocol)
    assert master is not None
    subscribe(master, "#")
    peers = []
    for login in logins:
        peer, rc = connect(port, login, protocol)
        assert peer is not None, f"{login.username} refused: {rc}"
        subscribe(peer, "#")  # asks for everything; the ACL must deliver only its own commands
        peers.append(peer)

    for sender, login in zip(peers, logins, strict=True):
        # Its own reports reach the master; each is the marker for the forbidden ones before it.
        for victim in logins:
            if victim is login:
                continue
            for topic in mosquitto.VEHICLE_TO_MASTER:
                forged = f"{victim.prefix}/{topic}"
                sender.client.publish(forged, b"forged report", qos=1)
                marker = f"marker-{uuid.uuid4().hex}".encode()
                sender.client.publish(f"{login.prefix}/state", marker, qos=1)
                assert master.wait_for(f"{login.prefix}/state", marker)
                assert not master.saw(forged, b"forged report"), f"{login.username} → {forged}"
                checked += 1
            for topic in victim.commands:
                forged = f"{victim.prefix}/{topic}"
                sender.client.publish(forged, b"forged command", qos=1)
                marker = f"marker-{uuid.uuid4().hex}".encode()
                sender.client.publish(f"{login.prefix}/state", marker, qos=1)
                assert master.wait_for(f"{login.prefix}/state", marker)
                victim_peer = peers[logins.index(victim)]
                assert not victim_peer.saw(forged, b"forged command"), (
                    f"{login.username} → {forged}"
                )
                checked += 1
        # A vehicle cannot command itself either (only the master writes commands).
        for topic in login.commands:
            sender.client.publish(f"{login.prefix}/{topic}", b"self command", qos=1)
        marker = f"marker-{uuid.uuid4().hex}".encode()
        sender.client.publish(f"{login.prefix}/connection", marker, qos=1)
        assert master.wait_for(f"{login.prefix}/connection", marker)
        assert not any(payload == b"self command" for _, payload in sender.received)
        checked += len(login.commands)

    # The master's commands reach exactly their vehicle, though every vehicle subscribed to '#'.
    for target in logins:
        for topic in target.commands:
            payload = f"command-{uuid.uuid4().hex}".encode()
            master.client.publish(f"{target.prefix}/{topic}", payload, qos=1)
            target_peer = peers[logins.index(target)]
            assert target_peer.wait_for(f"{target.prefix}/{topic}", payload)
            for other, other_peer in zip(logins, peers, strict=True):
                if other is not target:
                    marker = f"marker-{uuid.uuid4().hex}".encode()
                    master.client.publish(f"{other.prefix}/order", marker, qos=1)
                    assert other_peer.wait_for(f"{other.prefix}/order", marker)
                    assert not any(p == payload for _, p in other_peer.received), other.username
                    checked += 1
    # Vehicles never see each other's reports.
    for peer, login in zip(peers, logins, strict=True):
        foreign = [t for t, _ in peer.received if not t.startswith(login.prefix + "/")]
        assert foreign == [], f"{login.username} saw {foreign}"
    for peer in [master, *peers]:
        peer.client.loop_stop()
        peer.client.disconnect()
    print(f"MQTT {protocol}: {checked} forbidden combinations checked, none crossed")
    assert checked == 64  # 3 vehicles: 48 forged by vehicles, 16 misdirected


@pytest.mark.parametrize("protocol", [mqtt.MQTTv311, mqtt.MQTTv5], ids=["3.1.1", "5"])
def test_anonymous_and_wrong_passwords_are_refused(broker, protocol) -> None:
    port, master_login, logins = broker
    assert connect(port, None, protocol)[0] is None
    assert connect(port, Login(logins[0].username, "wrong"), protocol)[0] is None
    assert connect(port, Login("nobody", "x"), protocol)[0] is None
    peer, _ = connect(port, logins[0], protocol)
    assert peer is not None
    peer.client.loop_stop()
    peer.client.disconnect()


def test_the_generated_files_hold_only_enabled_logins_and_refuse_wildcards(tmp_path) -> None:
    vehicle = Vehicle.objects.create(manufacturer="Acme", serial_number="AGV-9")
    other = Vehicle.objects.create(manufacturer="Acme", serial_number="AGV-10")
    issue_mqtt_password(vehicle=vehicle)
    issue_mqtt_password(vehicle=other)
    other.mqtt_credential.enabled = False
    other.mqtt_credential.save()
    files = write_broker_files(
        directory=tmp_path,
        master_username="fleet",
        master_password="x",
        listeners=mosquitto.Listeners(
            port=1883, tls_port=8883, cafile="/ca.pem", certfile="/c.pem", keyfile="/k.pem"
        ),
    )
    config = files.config.read_text()
    assert "allow_anonymous false" in config
    assert "listener 8883" in config
    assert "certfile /c.pem" in config
    # control subscribes to the whole fleet: ~10 s of 1,000 vehicles' messages (docs/LOAD.md)
    assert "\nmax_queued_messages 20000\n" in config
    assert "Acme_AGV-9:$7$101$" in files.passwords.read_text()
    assert "AGV-10" not in files.passwords.read_text() + files.acl.read_text()
    with pytest.raises(ValueError, match="wildcard|'\\+'"):
        mosquitto.VehicleLogin("u", "h", "uagv", "2.0.0", "Acme", "AGV+1").rules()
    with pytest.raises(ValueError, match="TLS listener"):
        mosquitto.Listeners(tls_port=8883)
    with pytest.raises(ValueError, match="another vehicle"):
        issue_mqtt_password(vehicle=other, username="Acme_AGV-9")


def test_the_command_needs_the_masters_login_in_mqtt_url(tmp_path, settings) -> None:
    settings.MQTT_URL = "mqtt://127.0.0.1:1883"
    with pytest.raises(CommandError, match="MQTT_URL must carry"):
        call_command("mosquitto_config", "--out", str(tmp_path))
    settings.MQTT_URL = "mqtt://fleet:secret@127.0.0.1:1883"
    call_command("mosquitto_config", "--out", str(tmp_path))
    assert "user fleet" in (tmp_path / "acl").read_text()


@pytest.mark.skipif(shutil.which("openssl") is None, reason="openssl is not installed")
def test_the_tls_listener_serves_the_given_certificate(tmp_path) -> None:
    key, cert = tmp_path / "server.key", tmp_path / "server.pem"
    subprocess.run(
        ["openssl", "req", "-x509", "-newkey", "rsa:2048", "-nodes", "-days", "1",
         "-subj", "/CN=127.0.0.1", "-addext", "subjectAltName=IP:127.0.0.1",
         "-keyout", str(key), "-out", str(cert)],
        check=True, capture_output=True,
    )  # fmt: skip
    vehicle = Vehicle.objects.create(manufacturer="Acme", serial_number="AGV-T")
    username, password = issue_mqtt_password(vehicle=vehicle)
    plain, tls = free_port(), free_port()
    files = write_broker_files(
        directory=tmp_path,
        master_username="fleet",
        master_password="x",
        listeners=mosquitto.Listeners(
            port=plain,
            bind="127.0.0.1",
            tls_port=tls,
            certfile=str(cert),
            keyfile=str(key),
            extra=["user root"] if os.geteuid() == 0 else [],
        ),
    )
    process = subprocess.Popen(["mosquitto", "-c", str(files.config)], stderr=subprocess.PIPE)
    try:
        for _ in range(100):
            try:
                socket.create_connection(("127.0.0.1", tls), 0.2).close()
                break
            except OSError:
                time.sleep(0.05)
        client = mqtt.Client(callback_api_version=CallbackAPIVersion.VERSION2)
        client.tls_set(ca_certs=str(cert))
        client.username_pw_set(username, password)
        result: dict[str, object] = {}
        done = threading.Event()
        client.on_connect = lambda _c, _u, _f, rc, _p: (result.update(rc=rc), done.set())
        client.connect("127.0.0.1", tls)
        client.loop_start()
        assert done.wait(5)
        assert not result["rc"].is_failure  # type: ignore[attr-defined]
        client.loop_stop()
        client.disconnect()
    finally:
        process.terminate()
        process.wait(5)
