"""The live alert banner and the alert list in a real browser (Debian's Chromium): an alert
raised while the page is open shows up in the banner without a reload, and a person
acknowledges and resolves it with a comment."""

from typing import Any

import pytest
from django.test import Client

from alerts.models import Alert, Severity, Source
from alerts.services import raise_alert
from tests.browser import CHROMIUM_ARGS, in_thread
from tests.factories import user_with_role
from tests.orders.test_orders_page_browser import chromium  # noqa: F401 (fixture)

USERNAME, PASSWORD = "shiftlead", "alerts-page-password"
pytestmark = [pytest.mark.browser, pytest.mark.django_db(transaction=True)]


def test_the_banner_shows_a_new_alert_and_the_list_closes_it(
    live_server: Any,
    chromium: str,  # noqa: F811
) -> None:
    from playwright.sync_api import sync_playwright

    user = user_with_role("operator", USERNAME, password=PASSWORD)
    client = Client()
    client.force_login(user)
    session = client.cookies["sessionid"].value
    base = live_server.url
    with sync_playwright() as playwright:
        browser = playwright.chromium.launch(executable_path=chromium, args=CHROMIUM_ARGS)
        try:
            context = browser.new_context()
            # Log in through a session cookie: the login page is not what is tested here.
            context.add_cookies([{"name": "sessionid", "value": session, "url": base}])
            page = context.new_page()
            page.set_default_timeout(15_000)
            problems: list[str] = []
            page.on("pageerror", lambda e: problems.append(str(e)))
            page.goto(f"{base}/alerts/")
            assert page.locator("#alert-banner").is_hidden()

            alert = in_thread(
                lambda: raise_alert(
                    cause="connection:9",
                    source=Source.CONNECTION,
                    severity=Severity.URGENT,
                    message="AGV-9 connection broken",
                )
            )
            banner = page.locator("#alert-banner")
            banner.wait_for(state="visible", timeout=12_000)  # the banner polls every 5 s
            assert "AGV-9 connection broken" in banner.inner_text()
            assert "alert-urgent" in (banner.get_attribute("class") or "")

            page.reload()
            row = page.locator(f"tr[data-alert='{alert.pk}']")
            row.locator("input[name=comment]").fill("calling the technician")
            with page.expect_navigation():
                row.locator("button", has_text="Acknowledge").click()
            row = page.locator(f"tr[data-alert='{alert.pk}']")
            row.locator("input[name=comment]").fill("access point rebooted")
            with page.expect_navigation():
                row.locator("button", has_text="Resolve").click()
            assert page.locator(f"tr[data-alert='{alert.pk}']").count() == 0
            assert problems == []
        finally:
            browser.close()

    closed = in_thread(lambda: Alert.objects.get(pk=alert.pk))
    assert closed.status == Alert.Status.RESOLVED
    assert closed.acknowledge_comment == "calling the technician"
    assert closed.resolve_comment == "access point rebooted"
