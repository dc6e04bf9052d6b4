"""The staff orders page in a real browser (Debian's Chromium through Playwright), sized like a
tablet: log in, create a multi-stop order, reprioritise it, reassign it, cancel it."""

import os
from collections.abc import Iterator
from contextlib import contextmanager
from typing import Any

import pytest
from django.contrib.auth import get_user_model

from maps.models import Map
from orders.models import TransportOrder
from robots.models import Vehicle
from tests.browser import CHROMIUM, CHROMIUM_ARGS, in_thread, skip_or_fail
from tests.factories import VehicleFactory

USERNAME, PASSWORD = "shiftlead", "orders-page-password"
TIMEOUT_MS = 15_000

pytestmark = [pytest.mark.browser, pytest.mark.django_db(transaction=True)]


@pytest.fixture
def chromium() -> str:
    if not os.path.exists(CHROMIUM):
        skip_or_fail(f"Chromium not found at {CHROMIUM} (apt-get install chromium)")
    try:
        import playwright.sync_api  # noqa: F401
    except ImportError:
        skip_or_fail("playwright is not installed")
    return CHROMIUM


@contextmanager
def tablet(chromium: str) -> Iterator[tuple[Any, list[str]]]:
    """A touch page of a 10" tablet, and what went wrong on it (console errors, HTTP >= 400)."""
    from playwright.sync_api import sync_playwright

    with sync_playwright() as playwright:
        browser = playwright.chromium.launch(executable_path=chromium, args=CHROMIUM_ARGS)
        try:
            context = browser.new_context(
                viewport={"width": 1024, "height": 768}, has_touch=True, is_mobile=True
            )
            page = context.new_page()
            page.set_default_timeout(TIMEOUT_MS)
            problems: list[str] = []
            page.on(
                "console", lambda m: m.type == "error" and problems.append(f"console: {m.text}")
            )
            page.on("pageerror", lambda e: problems.append(f"pageerror: {e}"))
            page.on(
                "response",
                lambda r: r.status >= 400 and problems.append(f"http: {r.status} {r.url}"),
            )
            yield page, problems
        finally:
            browser.close()


def test_staff_create_change_and_cancel_a_multi_stop_order(
    live_server: Any, chromium: str, demo_map: Map
) -> None:
    get_user_model().objects.create_superuser(USERNAME, "lead@example.com", PASSWORD)
    vehicle = VehicleFactory(serial_number="AGV-TAB", connection=Vehicle.Connection.OFFLINE)
    base = live_server.url

    with tablet(chromium) as (page, problems):
        page.goto(f"{base}/orders/")
        page.wait_for_url("**/login/?next=/orders/")  # login required
        page.fill("#id_username", USERNAME)
        page.fill("#id_password", PASSWORD)
        page.click(".login-form [type=submit]")
        page.wait_for_url(f"{base}/orders/")
        problems.clear()  # the login page is not ours

        page.click("nav.orders-tabs >> text=New order")
        page.select_option("#id_step-0-station", label="demo/PICK-1")
        page.select_option("#id_step-1-station", label="demo/PICK-3")
        page.select_option("#id_step-1-operation", "ACTION")
        page.fill("#id_step-1-action_type", "detectObject")
        page.select_option("#id_step-2-station", label="demo/DROP-2")
        page.select_option("#id_step-2-operation", "DROP")
        page.fill("#id_external_ref", "TAB-1")
        page.tap("#order-create button[type=submit]")
        page.wait_for_url(f"{base}/orders/")  # the board
        assert "created" in page.locator(".messages").inner_text()
        assert "TAB-1" in page.locator(".board").inner_text()
        page.click("nav.orders-tabs >> text=All orders")
        row = page.locator("#orders-table tbody tr").first
        assert row.locator(".steps li").all_inner_texts() == [
            "PICK-1 pick",
            "PICK-3 detectObject",
            "DROP-2 drop",
        ]
        assert "no vehicle online" in row.locator(".reason").inner_text()

        row.locator("input[name=priority]").fill("9")
        with page.expect_navigation():
            row.locator("form[action$='/priority/'] button").tap()
        row = page.locator("#orders-table tbody tr").first
        assert row.locator("td.num").inner_text() == "9"
        row.locator("select[name=vehicle]").select_option(label="AGV-TAB")
        with page.expect_navigation():
            row.locator("form[action$='/reassign/'] button").tap()
        row = page.locator("#orders-table tbody tr").first
        assert "only AGV-TAB" in row.inner_text()
        with page.expect_navigation():
            row.locator("form[action$='/cancel/'] button").tap()
        assert "cancelled" in page.locator(".messages").inner_text()
        assert page.locator("#orders-table tbody tr").count() == 0  # only open orders listed
        page.goto(f"{base}/orders/?status=ALL")
        assert page.locator("#orders-table .badge").first.inner_text() == "cancelled"
        assert problems == []

    order = in_thread(lambda: TransportOrder.objects.select_related("intended_vehicle").get())
    assert (order.status, order.priority, order.external_ref) == ("CANCELLED", 9, "TAB-1")
    assert order.intended_vehicle == vehicle
