"""The live map in a real browser: a vehicle fed to a real Controller moves on the canvas.

Runs the ASGI application (HTTP + websockets) in a Daphne process through Channels'
`ChannelsLiveServerTestCase` and drives the system Chromium with Playwright (no browser
download). A `control.Controller` in this process takes VDA 5050 state messages and its
browser snapshot goes out through `control.service._broadcast_vehicles`, as `run_control` does,
so the channel layer must cross processes: Redis. Without Chromium or Redis the test is
skipped, unless FLEET_REQUIRE_SERVICES=1 (CI), where it fails instead.

The canvas has no DOM per vehicle; the page's `window.fleetMap` hook reports where it draws
each vehicle and where to click.
"""

import math
import os
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

import pytest
from channels.testing import ChannelsLiveServerTestCase
from django.conf import settings
from django.contrib.auth import get_user_model
from django.db import connections

import vda5050
from control.controller import Controller
from control.persistence import DjangoStore
from control.service import _broadcast_vehicles
from fleet.realtime import LIVE_GROUP, broadcast
from maps.demo import warehouse_layout
from maps.models import Station
from maps.services import create_layout
from orders.models import TransportOrder
from tests.browser import CHROMIUM, CHROMIUM_ARGS, in_thread, skip_or_fail

SCREENSHOT = Path("/tmp/live_map.png")
USERNAME, PASSWORD = "operator", "live-map-test-password"
TIMEOUT_MS = 15_000
SERIAL = "AGV-7"


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
    if any(
        connections[alias].vendor == "sqlite" and connections[alias].is_in_memory_db()
        for alias in connections
    ):
        return "the test database is in-memory SQLite, which a server process cannot share"
    return None


def _state(header_id: int, x: float, y: float, theta: float, ahead: list[str]) -> bytes:
    """A driving vehicle's state at (x, y): the first two nodes ahead released, the rest not."""
    return vda5050.encode(
        vda5050.State(
            header_id=header_id,
            timestamp=vda5050.now_timestamp("2.0.0"),
            version="2.0.0",
            manufacturer="Acme",
            serial_number=SERIAL,
            order_id="o-1",
            order_update_id=0,
            last_node_id="A1.1",
            last_node_sequence_id=0,
            driving=True,
            operating_mode=vda5050.OperatingMode.AUTOMATIC,
            node_states=[
                vda5050.NodeState(node_id=n, sequence_id=2 + 2 * i, released=i < 2)
                for i, n in enumerate(ahead)
            ],
            edge_states=[],
            action_states=[],
            battery_state=vda5050.BatteryState(battery_charge=81.0, charging=False),
            errors=[],
            loads=[vda5050.Load(load_id="L1", load_type="EPAL")],
            safety_state=vda5050.SafetyState(e_stop=vda5050.EStop.NONE, field_violation=False),
            agv_position=vda5050.AgvPosition(
                x=x, y=y, theta=theta, map_id="demo", position_initialized=True
            ),
        )
    )


class FedController:
    """A real Controller fed with state messages; `send` broadcasts what changed."""

    def __init__(self) -> None:
        self.controller = Controller(store=DjangoStore(), interface_name="uagv")
        self.header = 0
        in_thread(self.controller.load)

    def send(self, x: float, y: float, theta: float, ahead: list[str]) -> int | None:
        """Apply one state, flush (registers the vehicle), broadcast; the vehicle's pk."""
        self.header += 1
        payload = _state(self.header, x, y, theta, ahead)

        def work() -> int | None:
            self.controller.handle_message(f"uagv/v2/Acme/{SERIAL}/state", payload)
            self.controller.flush()
            vehicle = self.controller.fleet.vehicles[("Acme", SERIAL)]
            vehicle.needs_broadcast = True  # the flush may have registered it since
            _broadcast_vehicles(self.controller.collect_broadcast())  # as run_control does
            return vehicle.pk

        return in_thread(work)  # type: ignore[no-any-return]


@pytest.mark.browser
class LiveMapBrowserTest(ChannelsLiveServerTestCase):
    """Log in, see the layout on the canvas, watch a vehicle move, click it and a station."""

    @classmethod
    def setUpClass(cls) -> None:
        reason = _missing_requirement()
        if reason:
            skip_or_fail(reason)
        cls._pin_test_database_names()
        super().setUpClass()

    @classmethod
    def tearDownClass(cls) -> None:
        super().tearDownClass()
        for alias, test_name in cls._saved_test_names.items():
            settings.DATABASES[alias]["TEST"]["NAME"] = test_name

    @classmethod
    def _pin_test_database_names(cls) -> None:
        """Make the forked server process use the database this process already switched to
        (Channels would otherwise rename it to "test_test_…", django/channels#2185)."""
        cls._saved_test_names = {}
        for alias in connections:
            database = settings.DATABASES[alias]
            test = database.setdefault("TEST", {})
            cls._saved_test_names[alias] = test.get("NAME")
            test["NAME"] = connections[alias].settings_dict["NAME"]

    @contextmanager
    def _page(self) -> Iterator[Any]:
        from playwright.sync_api import sync_playwright

        with sync_playwright() as playwright:
            browser = playwright.chromium.launch(executable_path=CHROMIUM, args=CHROMIUM_ARGS)
            try:
                page = browser.new_page(viewport={"width": 1440, "height": 900})
                page.set_default_timeout(TIMEOUT_MS)
                messages: list[str] = []
                page.on("console", lambda m: messages.append(f"{m.type}: {m.text}"))
                page.on("pageerror", lambda e: messages.append(f"pageerror: {e}"))
                yield page, messages
            finally:
                browser.close()

    def _log_in(self, page: Any) -> None:
        page.goto(f"{self.live_server_url}/admin/login/?next=/")
        page.fill("#id_username", USERNAME)
        page.fill("#id_password", PASSWORD)
        page.click("input[type=submit]")
        page.wait_for_url(f"{self.live_server_url}/")

    def _drive_until_drawn(
        self, page: Any, feed: FedController, x: float, y: float, theta: float, ahead: list[str]
    ) -> str:
        """Send the state until the map draws the vehicle at rest at (x, y); its map key.

        Sent again every 2 s like control's periodic broadcasts, so an event that falls into a
        websocket reconnect is not lost for good.
        """
        from playwright.sync_api import TimeoutError as PlaywrightTimeout

        for _attempt in range(TIMEOUT_MS // 2000):
            key = str(feed.send(x, y, theta, ahead))
            try:
                page.wait_for_function(
                    """([key, x, y]) => {
                        const p = window.fleetMap && window.fleetMap.vehiclePosition(key);
                        return !!p && Math.abs(p.x - x) < 1e-3 && Math.abs(p.y - y) < 1e-3;
                    }""",
                    arg=[key, x, y],
                    timeout=2000,
                )
                return key
            except PlaywrightTimeout:
                continue
        raise AssertionError(f"vehicle never drawn at {(x, y)}")

    def _click_at(self, page: Any, point: dict[str, float]) -> None:
        page.mouse.click(point["x"], point["y"])

    def test_vehicle_moves_on_the_canvas_and_clicks_select(self) -> None:
        spec = warehouse_layout()
        create_layout(spec=spec)
        get_user_model().objects.create_superuser(USERNAME, "operator@example.com", PASSWORD)
        pick = Station.objects.get(station_id="PICK-2")
        drop = Station.objects.get(station_id="DROP-5")
        TransportOrder.objects.create(source=pick, destination=drop)
        feed = FedController()

        with self._page() as (page, console):
            self._log_in(page)
            console.clear()  # only the live page's own messages count

            page.wait_for_function("() => !!window.fleetMap")
            assert page.locator("canvas#map").is_visible()
            assert "PICK-2" in page.inner_text("#orders-table tbody")
            page.wait_for_selector('#connection[data-state="live"]')

            # A real Controller takes the vehicle's states; the map draws it where they say.
            key = self._drive_until_drawn(page, feed, 3.0, 3.0, 0.0, ["A2.1", "A3.1", "A4.1"])
            first = page.evaluate("(key) => window.fleetMap.vehiclePosition(key)", key)
            self._drive_until_drawn(page, feed, 6.0, 3.0, math.pi / 2, ["A3.1", "A4.1"])
            second = page.evaluate("(key) => window.fleetMap.vehiclePosition(key)", key)
            assert (first["x"], first["y"]) == pytest.approx((3.0, 3.0), abs=1e-3)
            assert (second["x"], second["y"]) == pytest.approx((6.0, 3.0), abs=1e-3)
            assert second["theta"] == pytest.approx(math.pi / 2, abs=1e-3)
            page.locator("#vehicles-table tbody tr", has_text=SERIAL).wait_for()
            assert page.inner_text("#vehicles-count") == "1"

            # Click the vehicle: it is selected and the details link to its page.
            self._click_at(
                page, page.evaluate("(key) => window.fleetMap.vehicleScreenPosition(key)", key)
            )
            assert page.evaluate("() => window.fleetMap.selection()") == {
                "kind": "vehicle",
                "key": key,
            }
            details = page.locator("#map-details")
            details.wait_for(state="visible")
            assert page.inner_text("#map-details .details-title") == SERIAL
            assert "A1.1" in details.inner_text()
            link = page.get_attribute("#map-details .details-link", "href")
            assert link == f"/vehicles/Acme/{SERIAL}/"
            assert page.locator("#vehicles-table tbody tr.selected", has_text=SERIAL).count() == 1

            # Click a station: its details replace the vehicle's.
            self._click_at(
                page, page.evaluate("() => window.fleetMap.stationScreenPosition('PICK-2')")
            )
            assert page.evaluate("() => window.fleetMap.selection()") == {
                "kind": "station",
                "id": "PICK-2",
            }
            assert page.inner_text("#map-details .details-title") == "PICK-2"
            assert page.is_hidden("#map-details .details-link")

            # Zoom with the button and the wheel, pan by dragging.
            before = page.evaluate("() => window.fleetMap.camera()")
            page.click('[data-map-action="zoom-in"]')
            zoomed = page.evaluate("() => window.fleetMap.camera()")
            assert zoomed["scale"] == pytest.approx(before["scale"] * 1.4)
            box = page.locator("canvas#map").bounding_box()
            centre = (box["x"] + box["width"] / 2, box["y"] + box["height"] / 2)
            page.mouse.move(*centre)
            page.mouse.wheel(0, -300)
            page.wait_for_function(
                "(scale) => window.fleetMap.camera().scale > scale", arg=zoomed["scale"]
            )
            panned_from = page.evaluate("() => window.fleetMap.camera()")
            page.mouse.down()
            page.mouse.move(centre[0] + 120, centre[1], steps=4)
            page.mouse.up()
            panned = page.evaluate("() => window.fleetMap.camera()")
            assert panned["cx"] < panned_from["cx"]  # dragging right shows what lies left
            # A drag is not a click: the station stays selected.
            assert page.evaluate("() => window.fleetMap.selection()")["kind"] == "station"

            # orders.changed makes the page fetch the orders again.
            second_order = in_thread(
                lambda: (
                    TransportOrder.objects.create(
                        source=pick,
                        destination=drop,
                        status=TransportOrder.Status.FAILED,
                        failure_reason="no vehicle",
                    ).pk
                )
            )
            in_thread(lambda: broadcast(LIVE_GROUP, "orders.changed", {"order": second_order}))
            page.wait_for_selector(f'#orders-table tbody tr[data-id="{second_order}"]')

            page.screenshot(path=str(SCREENSHOT))
            errors = [m for m in console if m.startswith(("error", "pageerror"))]
            assert not errors, errors
