"""`control` as leader or standby: terms of leadership, each with a fresh control loop.

A standby process does not connect to MQTT. When it takes the lock (`control.leader`) and its
guard time is over it builds a new control loop, exactly as a restarted `control` would: it
rebuilds from the database and adopts the orders vehicles are already driving. When leadership
is lost the loop stops without a final flush (another process may lead by then) and the process
goes back to standby. Every publish is checked against the lease (`Publisher.may_publish`).
"""

import logging
import threading
from collections import Counter
from collections.abc import Callable
from typing import Any

import paho.mqtt.client as mqtt
from django.db import connections
from paho.mqtt.enums import MQTTErrorCode

from control.leader import Leadership
from control.runner import ControlLoop

logger = logging.getLogger(__name__)


class StandbyControl:
    """Runs one control loop per term of leadership until `stop()`."""

    def __init__(
        self, leadership: Leadership | None, build_loop: Callable[[], ControlLoop]
    ) -> None:
        self.leadership, self.build_loop = leadership, build_loop
        self.loop: ControlLoop | None = None
        self.terms = 0
        self._stop = threading.Event()

    def stop(self) -> None:
        """Finish the running term and return from `run()`; safe from a signal handler."""
        self._stop.set()
        loop = self.loop
        if loop is not None:
            loop.stop()

    def run(self) -> None:
        """Compete, lead, step down, compete again … until stopped."""
        if self.leadership is None:  # no PostgreSQL (embedded demo): a single control process
            self._run_term()
            return
        self.leadership.start()
        try:
            while self.leadership.wait_until_leading(self._stop):
                try:
                    self._run_term()
                except Exception:  # e.g. the database went away while the term started
                    logger.exception("control term %d failed; trying again", self.terms)
                    self._stop.wait(1.0)
        finally:
            self.leadership.stop()

    def _run_term(self) -> None:
        self.terms += 1
        connections.close_all()  # Django's connections may be from before a database restart
        loop = self.build_loop()
        if self.leadership is not None:
            loop.leadership = self.leadership
            loop.controller.publisher.may_publish = self.leadership.holds_lease
            fence_mqtt_writes(
                loop.link.client, self.leadership.holds_lease, loop.controller.counters
            )
            logger.info("leading (fencing %s), term %d", self.leadership.fencing, self.terms)
        self.loop = loop
        if self._stop.is_set():
            return
        try:
            loop.run()
        finally:
            self.loop = None
            connections.close_all()

    def status(self) -> dict[str, Any]:
        """What `/health` and `/ready` report: role, fencing, lease, MQTT and database."""
        loop = self.loop
        mqtt_connected = loop is not None and loop.link.connected.is_set()
        if self.leadership is None:
            status: dict[str, Any] = {"role": "leader", "fencing": None, "holds_lease": True}
            status["database_ok"] = loop is not None
        else:
            status = self.leadership.status()
        status["mqtt_connected"] = mqtt_connected
        status["terms"] = self.terms
        status["ready"] = bool(
            status["role"] == "leader"
            and status["holds_lease"]
            and status["database_ok"]
            and mqtt_connected
        )
        return status


def fence_mqtt_writes(
    client: mqtt.Client, may_publish: Callable[[], bool], counters: Counter[str]
) -> None:
    """Check the lease again when paho's network thread writes, not only when we publish.

    `Publisher` asks before handing a message to paho, but paho writes it to the socket later
    from its own thread. A leader frozen in between would, on waking, send what was queued
    before the freeze, after the standby has taken over (seen once in the split-brain row). So
    every PUBLISH not yet started is dropped from paho's queue when the lease has run out. This
    reaches into paho 2.2's private `_packet_write`/`_out_packet` (pinned in requirements.txt).
    """
    write = client._packet_write  # noqa: SLF001

    def fenced_write() -> MQTTErrorCode:
        queue = client._out_packet  # noqa: SLF001
        if queue and not may_publish():
            for _ in range(len(queue)):
                packet = queue.popleft()
                unstarted_publish = packet["pos"] == 0 and packet["command"] & 0xF0 == mqtt.PUBLISH
                if unstarted_publish:
                    counters["publish_fenced_in_paho"] += 1
                else:
                    queue.append(packet)
        return write()

    client._packet_write = fenced_write  # type: ignore[method-assign]  # noqa: SLF001
