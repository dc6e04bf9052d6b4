"""What the browser tests share: Debian's Chromium, skipping honestly, ORM work off the
Playwright thread."""

import os
import shutil
import threading
from collections.abc import Callable
from typing import Any

import pytest
from django.db import connections

CHROMIUM = shutil.which("chromium") or "/usr/bin/chromium"
# As root, without the background-networking flags Chromium floods the closed network.
CHROMIUM_ARGS = [
    "--no-sandbox",
    "--disable-gpu",
    "--disable-background-networking",
    "--disable-component-update",
    "--no-first-run",
    "--disable-sync",
]


def skip_or_fail(reason: str) -> None:
    """Skip the test, or fail it where CI requires every service (FLEET_REQUIRE_SERVICES=1)."""
    if os.environ.get("FLEET_REQUIRE_SERVICES") == "1":
        pytest.fail(f"FLEET_REQUIRE_SERVICES=1 but {reason}")
    pytest.skip(reason)


def in_thread(function: Callable[[], Any]) -> Any:
    """Run `function` in a fresh thread and return its result.

    Playwright's sync API keeps an asyncio loop running in this thread, where Django's ORM and
    `async_to_sync` (used by `broadcast`) refuse to run.
    """
    outcome: dict[str, Any] = {}

    def target() -> None:
        try:
            outcome["value"] = function()
        except BaseException as error:  # re-raised in the caller
            outcome["error"] = error
        finally:
            connections.close_all()

    thread = threading.Thread(target=target)
    thread.start()
    thread.join(timeout=30)
    if "error" in outcome:
        raise outcome["error"]
    return outcome.get("value")
