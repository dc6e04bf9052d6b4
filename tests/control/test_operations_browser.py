"""The operations pages in Debian's Chromium: every page of the navigation loads without console
errors for an administrator on a tablet (1024×768 landscape, 768×1024 portrait), the overview's
counts match the database, the vehicles filter works, and the report shows the wait heatmap and
downloads its CSV."""

import os
import re
from datetime import timedelta
from pathlib import Path
from typing import Any

import pytest
from django.utils import timezone

from reports import waits
from reports.history import generate_history
from robots.models import Vehicle
from tests.browser import CHROMIUM, CHROMIUM_ARGS, in_thread, skip_or_fail
from tests.factories import VehicleFactory, user_with_role

pytestmark = [pytest.mark.browser, pytest.mark.django_db(transaction=True)]
TABLETS = [{"width": 1024, "height": 768}, {"width": 768, "height": 1024}]


@pytest.fixture
def chromium() -> str:
    if not os.path.exists(CHROMIUM):
        skip_or_fail(f"Chromium not found at {CHROMIUM} (apt-get install chromium)")
    try:
        import playwright.sync_api  # noqa: F401
    except ImportError:
        skip_or_fail("playwright is not installed")
    return CHROMIUM


def signed_in_page(browser: Any, live_server: Any, client: Any, viewport: dict[str, int]) -> Any:
    """A page carrying the session of `client` (force_login: django-axes is on)."""
    context = browser.new_context(viewport=viewport, accept_downloads=True)
    cookie = client.cookies["sessionid"]
    context.add_cookies([{"name": "sessionid", "value": cookie.value, "url": live_server.url}])
    page = context.new_page()
    page.set_default_timeout(15_000)
    return page


def watch_console(page: Any) -> list[str]:
    problems: list[str] = []
    page.on("console", lambda m: m.type == "error" and problems.append(f"{page.url}: {m.text}"))
    page.on("pageerror", lambda e: problems.append(f"{page.url}: {e}"))
    return problems


def test_every_page_of_the_navigation_loads_cleanly_on_a_tablet(
    live_server: Any, chromium: str, client: Any, demo_map: Any
) -> None:
    from playwright.sync_api import sync_playwright

    client.force_login(user_with_role("administrator"))
    VehicleFactory(serial_number="AGV-1")
    with sync_playwright() as playwright:
        browser = playwright.chromium.launch(executable_path=chromium, args=CHROMIUM_ARGS)
        try:
            for viewport in TABLETS:
                page = signed_in_page(browser, live_server, client, viewport)
                problems = watch_console(page)
                page.goto(f"{live_server.url}/overview/")
                # Narrower than 1400 px: the links sit behind the Menu button.
                assert not page.is_visible("#main-nav")
                page.click("label.nav-toggle-button")
                assert page.is_visible("#main-nav")
                links = page.eval_on_selector_all(
                    "#main-nav a", "links => links.map(a => [a.textContent.trim(), a.href])"
                )
                names = [name for name, _ in links]
                for wanted in ("Live map", "Overview", "Vehicles", "Orders", "Alerts", "Energy"):
                    assert wanted in names
                for wanted in ("Maintenance", "Inventory", "Reports", "Layouts", "Audit"):
                    assert wanted in names
                for name, href in links:
                    if name in ("API", "Admin"):  # not operations pages (Django's, DRF's)
                        continue
                    response = page.goto(href)
                    assert response is not None
                    assert response.status == 200, (name, href)
                    page.wait_for_load_state("load")
                    width = page.evaluate("document.documentElement.scrollWidth")
                    assert width <= viewport["width"] + 1, f"{name} scrolls sideways ({width} px)"
                # pytest-django's live server speaks HTTP only: the live map's websocket cannot
                # connect here (tests/control/test_live_map_browser.py runs it under ASGI).
                problems = [p for p in problems if "/ws/live/" not in p]
                assert problems == [], problems
                page.context.close()
        finally:
            browser.close()


def test_the_overview_counts_and_the_vehicles_filter(
    live_server: Any, chromium: str, client: Any, demo_map: Any
) -> None:
    from playwright.sync_api import sync_playwright

    client.force_login(user_with_role("operator"))
    VehicleFactory(serial_number="AGV-1")
    VehicleFactory(serial_number="AGV-2", battery_charge=10.0)
    VehicleFactory(serial_number="AGV-3", connection="OFFLINE")
    VehicleFactory(serial_number="AGV-4", driving=True)
    with sync_playwright() as playwright:
        browser = playwright.chromium.launch(executable_path=chromium, args=CHROMIUM_ARGS)
        try:
            page = signed_in_page(browser, live_server, client, TABLETS[0])
            problems = watch_console(page)
            page.goto(f"{live_server.url}/overview/")
            shown = {
                state: int(page.text_content(f'[data-state="{state}"] .tile-count') or "-1")
                for state in ("idle", "offline", "driving")
            }
            expected = in_thread(
                lambda: {
                    "idle": Vehicle.objects.filter(
                        connection="ONLINE", driving=False, charging=False
                    ).count(),
                    "offline": Vehicle.objects.exclude(connection="ONLINE").count(),
                    "driving": Vehicle.objects.filter(driving=True).count(),
                }
            )
            assert shown == expected == {"idle": 2, "offline": 1, "driving": 1}
            page.click('[data-state="offline"]')  # the tile links to the filtered list
            assert rows(page) == ["AGV-3"]
            page.select_option("#id_state", "")
            page.fill("#id_battery_below", "50")
            page.click("#vehicle-filters button[type=submit]")
            page.wait_for_load_state("load")
            assert rows(page) == ["AGV-2"]
            page.fill("#id_battery_below", "")
            page.fill("#id_q", "agv-4")
            page.click("#vehicle-filters button[type=submit]")
            page.wait_for_load_state("load")
            assert rows(page) == ["AGV-4"]
            assert (
                page.get_attribute('tr[data-vehicle="AGV-4"] a', "href") == "/vehicles/sim/AGV-4/"
            )
            assert problems == []
        finally:
            browser.close()


def rows(page: Any) -> list[str]:
    return page.eval_on_selector_all(
        "#vehicles-table tbody tr", "rows => rows.map(r => r.dataset.vehicle)"
    )


def test_the_report_shows_the_wait_heatmap_and_downloads_its_csv(
    live_server: Any, chromium: str, client: Any, demo_map: Any
) -> None:
    from playwright.sync_api import sync_playwright

    client.force_login(user_with_role("manager"))
    generate_history(vehicles=3, days=2, orders_per_hour=1)
    waits.roll_up_traffic_waits()
    today = timezone.localdate()
    with sync_playwright() as playwright:
        browser = playwright.chromium.launch(executable_path=chromium, args=CHROMIUM_ARGS)
        try:
            page = signed_in_page(browser, live_server, client, TABLETS[1])
            problems = watch_console(page)
            page.goto(f"{live_server.url}/reports/?start={today - timedelta(days=2)}&end={today}")
            page.wait_for_selector("#wait-heatmap svg.heatmap circle.heat")
            discs = page.locator("#wait-heatmap circle.heat").count()
            assert 3 <= discs <= 24
            box = page.locator("#wait-heatmap svg").bounding_box()
            assert box is not None
            assert box["width"] > 300
            with page.expect_download() as download_info:
                page.click("#traffic-waits h3 a.csv[href*='waits_nodes']")
            lines = Path(download_info.value.path()).read_text().splitlines()
            assert lines[0] == "map,node,x,y,waits,wait_s"
            assert len(lines) == 1 + discs
            assert re.match(r"^\S+,\S+,", lines[1])
            assert problems == []
        finally:
            browser.close()
