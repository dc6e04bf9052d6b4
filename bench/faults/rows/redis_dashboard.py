"""Dashboard convergence for the Redis row: a browser on the live page, and the vehicles' truth.

`LivePage` is the live page's websocket client as `static/fleet/live/main.js` runs it, through
the row's daphne: a logged-in session cookie, `vehicles.update` rows merged like
`applyVehicleUpdate` (whole rows replace, `changes` merge, None deletes), after a reconnect the
database snapshot `/live/vehicles.json` (then and 2 s later) merged like `applyVehicleSnapshot`
and `catchUp` (a row from before the reconnect takes the database's fields except those changed
since), and on every close the page's back-off (1 s · 2^attempts, ±25 %, at most 3 s,
attempts reset on open). `Truth` is an MQTT client of its own that records every position,
last node and order the vehicles report.

Convergence after a kill: from Redis accepting connections again (`redis_up`) to the first
`vehicles.update` the page receives after which every vehicle's row on the page is current: its
position within 1 cm, last node and order equal to what the vehicle reported in the 2 s before
(or its latest report, for a vehicle that stopped).
"""

import asyncio
import json
import random
import threading
import time
import urllib.request
import uuid
from collections import defaultdict, deque
from typing import Any

import paho.mqtt.client as mqtt
from paho.mqtt.enums import CallbackAPIVersion

WINDOW_S = 2.0  # a page row may show any report of the last 2 s (control → Redis → daphne)
POSITION_TOLERANCE_M = 0.01  # the page gets millimetres
LIVE_DATA_FRESH_S = 2.0  # main.js LIVE_DATA_FRESH_MS
CATCH_UP_AGAIN_S = 2.0  # main.js CATCH_UP_AGAIN_MS
RECONNECT_MIN_S, RECONNECT_MAX_S = 0.5, 1.0  # main.js RECONNECT_MIN_MS / RECONNECT_MAX_MS
SIGNED_OUT = {4401, 4403}

Report = tuple[float, float | None, float | None, str, str]  # (monotonic, x, y, node, order)


def login_session() -> str:
    """A session key of a superuser in the row's database (as bench/load/setup.py does)."""
    from django.contrib.auth import (
        BACKEND_SESSION_KEY,
        HASH_SESSION_KEY,
        SESSION_KEY,
        get_user_model,
    )
    from django.contrib.sessions.backends.db import SessionStore

    user = get_user_model().objects.create_superuser(f"faults-{uuid.uuid4().hex[:6]}", "", None)
    session = SessionStore()
    session[SESSION_KEY] = str(user.pk)
    session[BACKEND_SESSION_KEY] = "django.contrib.auth.backends.ModelBackend"
    session[HASH_SESSION_KEY] = user.get_session_auth_hash()
    session.create()
    return str(session.session_key)


class Truth:
    """What each vehicle reported (state and visualization), as the master receives it."""

    def __init__(self, url: str, interface: str) -> None:
        self.lock = threading.Lock()
        self.reports: dict[str, deque[Report]] = defaultdict(lambda: deque(maxlen=400))
        self._latest: dict[str, dict[str, Any]] = defaultdict(dict)
        host, port = url.removeprefix("mqtt://").split(":")
        self.client = mqtt.Client(
            callback_api_version=CallbackAPIVersion.VERSION2,
            client_id=f"truth-{uuid.uuid4().hex[:8]}",
        )
        self.client.reconnect_delay_set(min_delay=1, max_delay=1)
        topics = [(f"{interface}/+/+/+/{t}", 0) for t in ("state", "visualization")]
        self.client.on_connect = lambda client, *_: client.subscribe(topics)
        self.client.on_message = self._on_message
        self.client.connect(host, int(port), keepalive=10)
        self.client.loop_start()

    def _on_message(self, client: mqtt.Client, userdata: Any, msg: mqtt.MQTTMessage) -> None:
        parts = msg.topic.split("/")
        try:
            document = json.loads(msg.payload)
        except ValueError:
            return
        if not isinstance(document, dict):
            return
        with self.lock:
            latest = self._latest[parts[3]]
            position = document.get("agvPosition")
            if isinstance(position, dict):
                latest["x"], latest["y"] = position.get("x"), position.get("y")
            if parts[4] == "state":
                latest["node"] = document.get("lastNodeId") or ""
                latest["order"] = document.get("orderId") or ""
            self.reports[parts[3]].append(
                (
                    time.monotonic(),
                    latest.get("x"),
                    latest.get("y"),
                    latest.get("node", ""),
                    latest.get("order", ""),
                )
            )

    def current(self, serial: str, row: dict[str, Any], at: float) -> bool:
        """Whether the page's `row` shows a report of `serial` from [at − 2 s, at] or its
        latest one."""
        with self.lock:
            reports = list(self.reports.get(serial, ()))
        if not reports:
            return False
        recent = [r for r in reports if at - WINDOW_S <= r[0] <= at] + [reports[-1]]
        return any(_matches(row, report) for report in recent)

    def latest(self, serial: str) -> Report | None:
        with self.lock:
            reports = self.reports.get(serial)
            return reports[-1] if reports else None

    def serials(self) -> list[str]:
        with self.lock:
            return sorted(self.reports)

    def stop(self) -> None:
        self.client.loop_stop()
        self.client.disconnect()


def _matches(row: dict[str, Any], report: Report) -> bool:
    _, x, y, node, order = report
    if x is None or y is None or row.get("x") is None or row.get("y") is None:
        return False
    near = abs(row["x"] - x) <= POSITION_TOLERANCE_M and abs(row["y"] - y) <= POSITION_TOLERANCE_M
    return near and (row.get("last_node") or "") == node and (row.get("order") or "") == order


def _key(row: dict[str, Any]) -> str:
    """main.js `vehicleKey`."""
    if row.get("id") is None:
        return f"{row.get('manufacturer')}/{row.get('serial')}"
    return str(row["id"])


class LivePage(threading.Thread):
    """The live page's websocket, reconnecting like main.js; measures convergence per kill."""

    def __init__(self, base_url: str, session: str, truth: Truth) -> None:
        super().__init__(daemon=True, name="live-page")
        self.base_url, self.session, self.truth = base_url, session, truth
        self.rows: dict[str, dict[str, Any]] = {}  # vehicle key -> row, as main.js `vehicles`
        self.lock = threading.Lock()
        self.rng = random.Random(11)
        self.opens = self.closes = self.failed_handshakes = self.messages = 0
        self.up_at: float | None = None  # Redis up, convergence not yet seen
        self.convergence: list[float | None] = []
        self.closes_per_kill: list[int] = []
        # Per kill: what was still stale on the page at its last check before converging.
        self.stale_before: list[list[str]] = []
        self._stale: list[str] = []
        self._closes_at_kill = 0
        self._halt = threading.Event()

    # -- the row's kill loop calls these

    def redis_down(self) -> None:
        """A kill starts: a convergence still pending from the last one never came."""
        with self.lock:
            self._finish(None)
            self._closes_at_kill = self.closes

    def redis_up(self, at: float) -> None:
        with self.lock:
            self.up_at = at

    def wait_converged(self, timeout: float) -> None:
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline and self.up_at is not None:
            time.sleep(0.1)
        with self.lock:
            self._finish(None)

    def _finish(self, seconds: float | None) -> None:
        if self.up_at is not None:
            self.convergence.append(seconds)
            self.closes_per_kill.append(self.closes - self._closes_at_kill)
            self.stale_before.append(self._stale)
            self.up_at = None
        self._stale = []

    # -- the page

    def run(self) -> None:
        asyncio.run(self._run())

    def stop(self) -> None:
        self._halt.set()
        self.join(10)

    async def _run(self) -> None:
        import websockets

        url = self.base_url.replace("http://", "ws://") + "/ws/live/"
        headers = {"Cookie": f"sessionid={self.session}", "Origin": self.base_url}
        attempts, ever_opened = 0, False
        while not self._halt.is_set():
            code = None
            try:
                async with websockets.connect(url, additional_headers=headers, max_size=None) as ws:
                    self.opens += 1
                    attempts = 0
                    if ever_opened:  # main.js onSocketOpen: catch up from the database
                        with self.lock:
                            for row in self.rows.values():
                                row["since_open"] = set()
                        loop = asyncio.get_running_loop()
                        loop.run_in_executor(None, self._refresh)
                        loop.call_later(CATCH_UP_AGAIN_S, loop.run_in_executor, None, self._refresh)
                    ever_opened = True
                    while not self._halt.is_set():
                        try:
                            text = await asyncio.wait_for(ws.recv(), timeout=0.5)
                        except TimeoutError:
                            continue
                        self._on_message(str(text))
                    return
            except websockets.ConnectionClosed as closed:
                code = closed.rcvd.code if closed.rcvd is not None else None
                self.closes += 1
            except (OSError, websockets.InvalidHandshake, TimeoutError):
                self.failed_handshakes += 1
            if code in SIGNED_OUT:
                raise RuntimeError(f"live page refused: close code {code}")
            delay = min(RECONNECT_MAX_S, RECONNECT_MIN_S * 2**attempts)
            attempts += 1
            await asyncio.sleep(delay * (0.75 + self.rng.random() * 0.5))

    def _on_message(self, text: str) -> None:
        now = time.monotonic()
        message = json.loads(text)
        if message.get("event") != "vehicles.update":
            return
        payload = message.get("payload") or {}
        with self.lock:
            self.messages += 1
            for row in payload.get("vehicles") or []:  # applyVehicleUpdate
                if row.get("id") is not None:
                    self.rows.pop(f"{row.get('manufacturer')}/{row.get('serial')}", None)
                self.rows[_key(row)] = {**row, "live_at": now}
            for change in payload.get("changes") or []:
                known = self.rows.get(_key(change))
                if known is None:
                    continue
                for field, value in change.items():
                    if value is None:
                        known.pop(field, None)
                    else:
                        known[field] = value
                    if "since_open" in known:
                        known["since_open"].add(field)
                known["live_at"] = now
            if self.up_at is not None and now >= self.up_at and self._current(now):
                self._finish(round(now - self.up_at, 3))

    def _current(self, now: float) -> bool:
        serials = self.truth.serials()
        by_serial = {row.get("serial"): row for row in self.rows.values()}
        stale = [
            s for s in serials if s not in by_serial or not self.truth.current(s, by_serial[s], now)
        ]
        if stale:
            self._stale = [self._describe(s, by_serial.get(s), now) for s in stale]
        return bool(serials) and not stale

    def _describe(self, serial: str, row: dict[str, Any] | None, now: float) -> str:
        """One stale vehicle: the page's row against the vehicle's latest report."""
        if row is None:
            return f"{serial}: no row"
        latest = self.truth.latest(serial)
        shown = (row.get("x"), row.get("y"), row.get("last_node"), row.get("order"))
        age = round(now - row.get("live_at", 0), 1)
        since_up = round(now - (self.up_at or now), 1)
        return f"{serial} t+{since_up}: page {shown} ({age} s old) vs {latest and latest[1:]}"

    def _refresh(self) -> None:
        """main.js refreshVehicles + applyVehicleSnapshot (the routes aside)."""
        request = urllib.request.Request(
            self.base_url + "/live/vehicles.json",
            headers={"Cookie": f"sessionid={self.session}", "Accept": "application/json"},
        )
        try:
            with urllib.request.urlopen(request, timeout=10) as response:
                rows = json.loads(response.read())["vehicles"]
        except (OSError, ValueError, KeyError):
            return
        now = time.monotonic()
        with self.lock:
            for row in rows:
                known = self.rows.get(_key(row))
                if known and "since_open" in known:  # main.js catchUp
                    fresh = known["since_open"]
                    known.update({k: v for k, v in row.items() if v is not None and k not in fresh})
                    continue
                if known and now - known.get("live_at", 0) < LIVE_DATA_FRESH_S:
                    continue
                self.rows[_key(row)] = {**(known or {}), **row}
