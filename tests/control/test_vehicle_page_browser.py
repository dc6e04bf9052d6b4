"""The vehicle page in a real browser: "Pause" reaches a simulated vehicle, which reports it.

Everything is real except the browser's user: the ASGI application (pages + websockets) runs in
a Daphne process through Channels' `ChannelsLiveServerTestCase`; `control`'s loop (Controller,
paho link, command queue, broadcasts) runs in a thread of this process; one simulated vehicle
runs as a process on Mosquitto, on an interface name of its own. The page's websocket asks
`control` to watch the vehicle, the Pause button goes through the audited command service and
the command queue, `control` publishes `startPause`, the simulator pauses and its next state
says `paused: true`, which the page shows. Needs Chromium, Redis (the channel layer and command
queue cross processes) and Mosquitto; skipped without them unless FLEET_REQUIRE_SERVICES=1.
"""

import json
import os
import sys
import tempfile
import threading
import time
import uuid
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

import pytest
import redis
from channels.testing import ChannelsLiveServerTestCase
from django.conf import settings
from django.db import connections

from control.controller import Controller
from control.persistence import DjangoStore
from control.runner import ControlLoop, MqttLink
from control.service import _broadcast_vehicles, _stream_vehicle
from fleet import roles
from fleet.control_queue import QUEUE_KEY, receive_commands
from fleet.mqtt import make_client
from maps.demo import warehouse_layout
from maps.models import Station
from maps.selectors import layout_as_dict
from maps.services import create_layout
from orders.models import TransportOrder
from orders.tasks import dispatch_pending_orders_task
from robots.models import Vehicle
from tests.browser import CHROMIUM, CHROMIUM_ARGS, in_thread, skip_or_fail
from tests.e2e.processes import Process
from tests.factories import user_with_role

SCREENSHOT = Path("/tmp/vehicle_page.png")
ORDER_SCREENSHOT = Path("/tmp/vehicle_page_order.png")
TIMEOUT_MS = 40_000  # a loaded 2-core machine (load 20+) is slow
SERIAL = "AGV-1"


def _missing_requirement() -> str | None:
    """Why this test cannot run here, or None."""
    if not os.path.exists(CHROMIUM):
        return f"Chromium not found at {CHROMIUM} (apt-get install chromium)"
    try:
        import playwright.sync_api  # noqa: F401
    except ImportError:
        return "playwright is not installed"
    if "channels_redis" not in settings.CHANNEL_LAYERS["default"]["BACKEND"]:
        return "REDIS_URL unset: the in-memory channel layer cannot reach the server process"
    if not settings.SERVICES.get("MQTT_URL", "").startswith("mqtt"):
        return "no Mosquitto: the simulated vehicle needs a broker"
    if any(connections[alias].vendor == "sqlite" for alias in connections):
        return "the test database is SQLite, which the server process cannot share"
    return None


def _wait(condition: Callable[[], object], timeout: float, what: str, logs: Process) -> Any:
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        value = condition()
        if value:
            return value
        time.sleep(0.25)
    raise AssertionError(f"timed out: {what}\n--- simulator ---\n{logs.output()[-3000:]}")


@pytest.mark.browser
class VehiclePageBrowserTest(ChannelsLiveServerTestCase):
    """Open the page of a simulated vehicle, press Pause, see it paused."""

    @classmethod
    def setUpClass(cls) -> None:
        reason = _missing_requirement()
        if reason:
            skip_or_fail(reason)
        cls._saved_test_names = {}
        for alias in connections:  # the forked server must use this database (channels#2185)
            test = settings.DATABASES[alias].setdefault("TEST", {})
            cls._saved_test_names[alias] = test.get("NAME")
            test["NAME"] = connections[alias].settings_dict["NAME"]
        super().setUpClass()

    @classmethod
    def tearDownClass(cls) -> None:
        super().tearDownClass()
        for alias, test_name in cls._saved_test_names.items():
            settings.DATABASES[alias]["TEST"]["NAME"] = test_name

    @contextmanager
    def _control(self, interface: str) -> Iterator[Controller]:
        """`control`'s loop in a thread, as `run_control` wires it, on our interface name."""
        redis.Redis.from_url(settings.REDIS_URL).delete(QUEUE_KEY)  # no leftovers of old runs
        # Two nodes of base ahead, the rest horizon: the page draws both.
        controller = Controller(store=DjangoStore(), interface_name=interface, base_ahead=2)
        client, address = make_client(settings.MQTT_URL, client_id_prefix="vehicle-page-test")
        loop = ControlLoop(
            controller,
            MqttLink(client, address.host, address.port, controller),
            receive_commands=receive_commands,
            broadcast=_broadcast_vehicles,
            intervals=settings.FLEET_CONTROL | {"FLUSH_INTERVAL": 0.3},
            stream_vehicle=_stream_vehicle,
        )

        def run() -> None:
            try:
                loop.run()
            finally:
                connections.close_all()

        thread = threading.Thread(target=run, name="control", daemon=True)
        thread.start()
        try:
            yield controller
        finally:
            loop.stop()
            thread.join(timeout=20)

    @contextmanager
    def _simulator(self, interface: str, layout_file: Path, log_dir: Path) -> Iterator[Process]:
        argv = [sys.executable, "-m", "simulator", "--count", "1", "--layout", str(layout_file)]
        argv += ["--broker", settings.MQTT_URL, "--interface", interface, "--time-scale", "2"]
        argv += ["--state-interval", "1", "--visualization-hz", "1"]
        env = {k: v for k, v in os.environ.items() if not k.startswith("PYTEST")}
        process = Process("simulator", argv, env, log_dir)
        try:
            yield process
        finally:
            process.terminate()

    @contextmanager
    def _page(self, user: Any) -> Iterator[tuple[Any, list[str]]]:
        from playwright.sync_api import sync_playwright

        self.client.force_login(user)
        session = self.client.cookies["sessionid"].value
        with sync_playwright() as playwright:
            browser = playwright.chromium.launch(executable_path=CHROMIUM, args=CHROMIUM_ARGS)
            try:
                context = browser.new_context(viewport={"width": 1440, "height": 1000})
                context.add_cookies(
                    [{"name": "sessionid", "value": session, "url": self.live_server_url}]
                )
                page = context.new_page()
                page.set_default_timeout(TIMEOUT_MS)
                console: list[str] = []
                page.on("console", lambda m: console.append(f"{m.type}: {m.text}"))
                page.on("pageerror", lambda e: console.append(f"pageerror: {e}"))
                yield page, console
            finally:
                browser.close()

    def test_pause_button_pauses_the_simulated_vehicle(self) -> None:
        layout = create_layout(spec=warehouse_layout())
        interface = f"vp{uuid.uuid4().hex[:8]}"
        operator = user_with_role(roles.OPERATOR, username="vehicle-page-operator")
        with tempfile.TemporaryDirectory() as tmp:
            layout_file = Path(tmp) / "layout.json"
            layout_file.write_text(json.dumps(layout_as_dict(map=layout)))
            with (
                self._control(interface) as controller,
                self._simulator(interface, layout_file, Path(tmp)) as simulator,
            ):
                _wait(
                    lambda: Vehicle.objects.filter(
                        serial_number=SERIAL, connection=Vehicle.Connection.ONLINE, map_id="demo"
                    ).exists(),
                    30,
                    "the simulated vehicle registered, online, on the demo map",
                    simulator,
                )
                with self._page(operator) as (page, console):
                    self._pause_on_the_page(page)
                    # What the vehicle itself said last: paused (control's log of the wire).
                    assert _last_state(controller)["paused"] is True
                    page.screenshot(path=str(SCREENSHOT), full_page=True)
                    self._follow_and_cancel_an_order(page)
                    errors = [m for m in console if m.startswith(("error", "pageerror"))]
                    assert not errors, errors

    def _pause_on_the_page(self, page: Any) -> None:
        page.goto(f"{self.live_server_url}/vehicles/sim/{SERIAL}/")
        page.wait_for_selector('#connection[data-state="live"]')
        # The watch started: control streams the vehicle's messages to the page.
        page.wait_for_selector('.chip[data-topic="state"].has-data')
        page.wait_for_selector('.chip[data-topic="connection"].has-data')
        assert page.inner_text("#s-paused") == "no"
        assert page.inner_text("#h-manufacturer") == "sim"
        assert "ONLINE" in page.inner_text("#h-connection")
        assert "x " in page.inner_text("#h-position")
        page.click('.chip[data-topic="state"]')
        assert '"serialNumber": "AGV-1"' in page.inner_text("#json-view")

        page.click('button[data-action="pause"]')

        page.wait_for_selector('#command-status[data-state="ok"]')
        page.wait_for_function(
            "document.getElementById('s-paused').textContent === 'yes'", timeout=TIMEOUT_MS
        )
        page.wait_for_selector('.chip[data-topic="instantActions"].has-data')
        outgoing = page.locator('#log-table tr.dir-out[data-topic="instantActions"]')
        outgoing.filter(has_text="startPause").first.wait_for()
        page.select_option("#filter-direction", "out")
        assert page.locator("#log-table tr.dir-in").count() == 0
        finished = page.locator("#actions-table tbody tr", has_text="startPause")
        finished.filter(has_text="FINISHED").first.wait_for()
        assert in_thread(lambda: Vehicle.objects.get(serial_number=SERIAL).commands.count()) == 1

    def _follow_and_cancel_an_order(self, page: Any) -> None:
        """Resume, get an order, see it drawn base/horizon and traversed, cancel it (confirmed)."""
        page.click('button[data-action="resume"]')
        page.wait_for_function("document.getElementById('s-paused').textContent === 'no'")
        _wait_in_thread(
            lambda: not Vehicle.objects.get(serial_number=SERIAL).paused, "paused flushed false"
        )
        order = in_thread(_create_and_dispatch_order)
        assert order.vehicle_id is not None, "dispatch gave the order to the vehicle"

        page.wait_for_selector('.chip[data-topic="order"].has-data')
        page.wait_for_selector("#vmap .o-edge.base", state="attached")  # thin lines
        page.wait_for_selector("#vmap .o-node.horizon")
        page.wait_for_selector("#vmap .o-node.base.done", timeout=60_000)  # one node behind it
        page.screenshot(path=str(ORDER_SCREENSHOT), full_page=True)
        page.wait_for_function("document.getElementById('s-order').textContent !== '–'")
        page.click('.chip[data-topic="order"]')
        sent_order = json.loads(page.inner_text("#json-view"))
        assert page.inner_text("#s-order") == sent_order["orderId"]
        assert any(not node["released"] for node in sent_order["nodes"])  # a horizon

        dialogs: list[str] = []

        def confirm(dialog: Any) -> None:
            dialogs.append(dialog.message)
            dialog.accept()

        page.once("dialog", confirm)
        page.click('button[data-action="cancel_order"]')
        page.wait_for_selector('#command-status[data-state="ok"]')
        assert dialogs
        assert "Cancel" in dialogs[0]
        _wait_in_thread(
            lambda: (
                TransportOrder.objects.get(pk=order.pk).status == TransportOrder.Status.CANCELLED
            ),
            "the order cancelled",
        )


def _last_state(controller: Controller) -> dict[str, Any]:
    with controller.lock:
        latest = controller.messages.latest(("sim", SERIAL))["state"]
    return dict(json.loads(latest.payload))


def _create_and_dispatch_order() -> TransportOrder:
    order = TransportOrder.objects.create(
        source=Station.objects.get(station_id="PICK-6"),
        destination=Station.objects.get(station_id="DROP-1"),
    )
    dispatch_pending_orders_task.delay()  # eager in tests
    order.refresh_from_db()
    return order


def _wait_in_thread(condition: Callable[[], bool], what: str, timeout: float = 60) -> None:
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        if in_thread(condition):
            return
        time.sleep(0.3)
    raise AssertionError(f"timed out: {what}")
