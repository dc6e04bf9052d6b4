"""A master-control-like MQTT subscriber for the simulator's broker tests.

Each test uses its own interface name (``simtest<random>``) so runs never see each other's
retained messages; :meth:`Recorder.close` clears the retained topics afterwards.
"""

from __future__ import annotations

import json
import socket
import threading
import time
import uuid
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import paho.mqtt.client as mqtt
import pytest
from paho.mqtt.enums import CallbackAPIVersion

HOST, PORT = "127.0.0.1", 1883


def _broker_up() -> bool:
    try:
        with socket.create_connection((HOST, PORT), timeout=1.0):
            return True
    except OSError:
        return False


#: Mark a module with this to skip it when no broker answers.
needs_broker = pytest.mark.skipif(not _broker_up(), reason="no MQTT broker on 127.0.0.1:1883")


@dataclass
class Received:
    """One message seen by the recorder."""

    topic: str
    data: dict[str, Any]
    retain: bool
    at: float = field(default_factory=time.monotonic, compare=False)

    @property
    def serial(self) -> str:
        return self.topic.split("/")[3]

    @property
    def kind(self) -> str:
        return self.topic.split("/")[4]


class Recorder:
    """A master-control-like subscriber that records everything under one interface."""

    def __init__(self, interface: str, major: str = "v2") -> None:
        self.interface = interface
        self.major = major
        self.messages: list[Received] = []
        self._cond = threading.Condition()
        self.client = mqtt.Client(CallbackAPIVersion.VERSION2, client_id=f"rec-{uuid.uuid4()}")
        self.client.on_message = self._on_message
        self.client.connect(HOST, PORT, 15)
        self.client.loop_start()

    def subscribe(self) -> None:
        info = self.client.subscribe(f"{self.interface}/{self.major}/+/+/#", qos=1)
        assert info[0] == mqtt.MQTT_ERR_SUCCESS

    def _on_message(self, _c: mqtt.Client, _u: object, msg: mqtt.MQTTMessage) -> None:
        if not msg.payload:
            return  # our own retained-message cleanup
        with self._cond:
            self.messages.append(Received(msg.topic, json.loads(msg.payload), bool(msg.retain)))
            self._cond.notify_all()

    def wait_for(self, predicate: Callable[[Received], bool], timeout: float = 10.0) -> Received:
        deadline = time.monotonic() + timeout
        with self._cond:
            while True:
                for message in self.messages:
                    if predicate(message):
                        return message
                remaining = deadline - time.monotonic()
                if remaining <= 0:
                    kinds = [(m.serial, m.kind) for m in self.messages[-10:]]
                    raise AssertionError(f"no matching message within {timeout} s; last: {kinds}")
                self._cond.wait(remaining)

    def publish(self, serial: str, kind: str, payload: bytes) -> None:
        self.client.publish(f"{self.interface}/{self.major}/sim/{serial}/{kind}", payload, qos=0)

    def close(self, serials: list[str]) -> None:
        # Clear the retained connection/factsheet messages this test left on the broker.
        for serial in serials:
            for kind in ("connection", "factsheet"):
                info = self.client.publish(
                    f"{self.interface}/{self.major}/sim/{serial}/{kind}", b"", qos=1, retain=True
                )
                info.wait_for_publish(5)
        self.client.disconnect()
        self.client.loop_stop()


def connection(serial: str, state: str) -> Callable[[Received], bool]:
    """Predicate: a ``connection`` message of ``serial`` reporting ``state``."""
    return lambda m: (
        m.serial == serial and m.kind == "connection" and m.data["connectionState"] == state
    )
