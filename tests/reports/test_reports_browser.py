"""The report page in a real browser (Debian's Chromium via Playwright): charts and CSV export."""

import os
from datetime import timedelta
from pathlib import Path
from typing import Any

import pytest
from django.utils import timezone

from reports.history import generate_history
from tests.browser import CHROMIUM, CHROMIUM_ARGS, skip_or_fail
from tests.factories import user_with_role

pytestmark = [pytest.mark.browser, pytest.mark.django_db(transaction=True)]
SCREENSHOT = Path("/tmp/reports.png")


@pytest.fixture
def chromium() -> str:
    if not os.path.exists(CHROMIUM):
        skip_or_fail(f"Chromium not found at {CHROMIUM} (apt-get install chromium)")
    try:
        import playwright.sync_api  # noqa: F401
    except ImportError:
        skip_or_fail("playwright is not installed")
    return CHROMIUM


def test_a_manager_sees_the_charts_and_downloads_a_csv(live_server: Any, chromium: str) -> None:
    from playwright.sync_api import sync_playwright

    user_with_role("manager", "manager", password="report-reader-pw")
    generate_history(vehicles=5, days=3, orders_per_hour=4)
    today = timezone.localdate()
    url = f"/reports/?start={today - timedelta(days=3)}&end={today}"
    with sync_playwright() as playwright:
        browser = playwright.chromium.launch(executable_path=chromium, args=CHROMIUM_ARGS)
        try:
            page = browser.new_page(viewport={"width": 1280, "height": 900}, accept_downloads=True)
            page.set_default_timeout(15_000)
            problems: list[str] = []
            page.on("console", lambda m: m.type == "error" and problems.append(m.text))
            page.on("pageerror", lambda e: problems.append(str(e)))
            page.goto(f"{live_server.url}{url}")  # login required: the login page, then back
            page.fill("#id_username", "manager")
            page.fill("#id_password", "report-reader-pw")
            page.click("button[type=submit]")
            page.wait_for_selector("svg.chart rect.bar-finished")
            assert page.locator("svg.chart").count() == 5  # with the traffic-wait chart
            assert page.locator("#utilisation svg.chart rect.bar-busy").count() == 5
            page.screenshot(path=str(SCREENSHOT), full_page=True)
            with page.expect_download() as download_info:
                page.click("#throughput a.csv")
            download = download_info.value
            lines = Path(download.path()).read_text().splitlines()
            assert lines[0] == "hour,finished,failed,cancelled"
            assert len(lines) == 1 + 4 * 24
            assert problems == []
        finally:
            browser.close()
