"""The live page in a real browser: the layout as SVG, vehicles moving on websocket events.

Runs the ASGI application (HTTP + websockets) in a Daphne process through Channels'
`ChannelsLiveServerTestCase` and drives the system Chromium with Playwright (no browser
download). Events are broadcast from this process, so the channel layer must cross processes:
Redis. Without Chromium or Redis the test is skipped, unless FLEET_REQUIRE_SERVICES=1 (CI),
where it fails instead.
"""

import math
import os
import re
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

import pytest
from channels.testing import ChannelsLiveServerTestCase
from django.conf import settings
from django.contrib.auth import get_user_model
from django.db import connections

from fleet.realtime import LIVE_GROUP, broadcast
from maps.demo import warehouse_layout
from maps.models import Station
from maps.services import create_layout
from orders.models import TransportOrder
from tests.browser import CHROMIUM, CHROMIUM_ARGS, in_thread, skip_or_fail

SCREENSHOT = Path("/tmp/live_page.png")
USERNAME, PASSWORD = "operator", "live-page-test-password"
TIMEOUT_MS = 15_000


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


def _vehicle_row(**fields: Any) -> dict[str, Any]:
    row = {
        "id": 9001,
        "manufacturer": "Acme",
        "serial": "AGV-7",
        "status": "driving",
        "connection": "ONLINE",
        "x": 3.0,
        "y": 3.0,
        "theta": 0.0,
        "map": "demo",
        "battery": 81.0,
        "mode": "AUTOMATIC",
        "order": "o-1",
        "transport_order": None,
        "last_node": "A1.1",
        "loaded": True,
        "errors": [],
        "base": [],
        "horizon": [],
    }
    row.update(fields)
    return row


def _send_vehicles(*rows: dict[str, Any]) -> None:
    in_thread(lambda: broadcast(LIVE_GROUP, "vehicles.update", {"vehicles": list(rows)}))


def _translate(transform: str | None) -> tuple[float, float]:
    match = re.search(r"translate\(\s*([-\d.e]+)[ ,]+([-\d.e]+)\s*\)", transform or "")
    assert match, f"no translate() in transform {transform!r}"
    return float(match.group(1)), float(match.group(2))


@pytest.mark.browser
class LivePageBrowserTest(ChannelsLiveServerTestCase):
    """Log in, see the demo layout, watch a vehicle appear and move over the websocket."""

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
        """Make the forked server process use the database this process already switched to.

        Channels' server setup renames NAME to "test_" + NAME unless TEST.NAME is set; after a
        fork NAME is already the test database, which would give "test_test_…"
        (django/channels#2185). Pinning TEST.NAME to the current name avoids that.
        """
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

    def _send_and_wait(
        self, page: Any, rows: list[dict[str, Any]], x: float, y: float
    ) -> tuple[float, float]:
        """Broadcast `rows` until vehicle 9001 is drawn at layout (x, y); return its translate.

        Sent again every 2 s like control's periodic broadcasts, so an event that falls into a
        websocket reconnect is not lost for good.
        """
        from playwright.sync_api import TimeoutError as PlaywrightTimeout

        for _attempt in range(TIMEOUT_MS // 2000):
            _send_vehicles(*rows)
            try:
                return self._wait_for_vehicle_at(page, x, y, timeout=2000)
            except PlaywrightTimeout:
                continue
        return self._wait_for_vehicle_at(page, x, y, timeout=TIMEOUT_MS)

    def _wait_for_vehicle_at(
        self, page: Any, x: float, y: float, timeout: float
    ) -> tuple[float, float]:
        """Wait until vehicle 9001 is drawn at layout (x, y), SVG (x, -y); return its translate."""
        page.wait_for_function(
            """([x, y]) => {
                const group = document.querySelector('#map .vehicle[data-id="9001"]');
                const match = group && /translate\\(([-\\d.e]+) ([-\\d.e]+)\\)/.exec(
                    group.getAttribute('transform') || '');
                return !!match && Math.abs(Number(match[1]) - x) < 1e-3
                    && Math.abs(Number(match[2]) + y) < 1e-3;
            }""",
            arg=[x, y],
            timeout=timeout,
        )
        return _translate(page.get_attribute('#map .vehicle[data-id="9001"]', "transform"))

    def test_layout_and_vehicle_moving_over_websocket(self) -> None:
        spec = warehouse_layout()
        create_layout(spec=spec)
        get_user_model().objects.create_superuser(USERNAME, "operator@example.com", PASSWORD)
        pick = Station.objects.get(station_id="PICK-2")
        drop = Station.objects.get(station_id="DROP-5")
        TransportOrder.objects.create(source=pick, destination=drop)

        with self._page() as (page, console):
            self._log_in(page)
            console.clear()  # only the live page's own messages count

            # The layout: one dot per node, one labelled square per station.
            page.wait_for_selector("#map .node")
            assert page.locator("#map .node").count() == len(spec["nodes"])
            assert page.locator("#map .station").count() == len(spec["stations"])
            labels = page.locator("#map .station-label").all_text_contents()
            assert sorted(labels) == sorted(s["name"] for s in spec["stations"])
            assert page.locator("#map .edge").count() > 0
            view_box = [float(v) for v in page.get_attribute("#map", "viewBox").split()]
            top, bottom = view_box[1], view_box[1] + view_box[3]
            assert top < -14, view_box  # y flipped: the highest node (y = 14 m) is at the top
            assert bottom > 2, view_box  # and the lowest (y = -2 m) at the bottom

            # The orders table shows the order created above.
            assert "PICK-2" in page.inner_text("#orders-table tbody")

            # The websocket is joined to the live group before anything is broadcast.
            page.wait_for_selector('#connection[data-state="live"]')

            route = {"base": [[6.0, 3.0], [6.0, 9.0]], "horizon": [[9.0, 9.0], [12.0, 9.0]]}
            parked = _vehicle_row(
                id=9002,
                serial="AGV-2",
                status="charging",
                x=23.0,
                y=3.0,
                theta=math.pi,
                loaded=False,
                order="",
                last_node="S-CHARGE-1",
                battery=14.0,
            )
            first = self._send_and_wait(
                page, [_vehicle_row(x=3.0, y=3.0, **route), parked], 3.0, 3.0
            )
            label = page.locator('#map .vehicle[data-id="9001"] .vehicle-label')
            assert label.text_content() == "AGV-7"
            assert page.is_visible('#map .vehicle[data-id="9001"] .vehicle-load')
            assert page.get_attribute('#map .route-base[data-id="9001"]', "points")
            assert page.get_attribute('#map .route-horizon[data-id="9001"]', "points")

            moved = _vehicle_row(
                x=6.0,
                y=4.5,
                theta=math.pi / 2,
                errors=["WARNING obstacle"],
                base=[[6.0, 9.0]],
                horizon=route["horizon"],
            )
            second = self._send_and_wait(page, [moved, parked], 6.0, 4.5)
            assert second != first
            assert second == pytest.approx((6.0, -4.5), abs=1e-3)

            vehicles_table = page.locator("#vehicles-table tbody")
            vehicles_table.filter(has_text="obstacle").wait_for()
            assert "AGV-7" in vehicles_table.inner_text()
            assert "AGV-2" in vehicles_table.inner_text()
            assert page.locator("#vehicles-count").inner_text() == "2"

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

            page.screenshot(path=str(SCREENSHOT), full_page=True)
            errors = [m for m in console if m.startswith(("error", "pageerror"))]
            assert not errors, errors
