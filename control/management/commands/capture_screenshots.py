"""`manage.py capture_screenshots`: PNGs of the main pages for the README (docs/screenshots/).

Starts the demo (`manage.py run_demo`) as a child process on a free port with a throw-away
SQLite database and its own embedded MQTT broker port, after filling a week of generated report
history, lets the simulated vehicles work for a while, signs in as the demo administrator in
Debian's Chromium (Playwright, never a downloaded browser) and saves one PNG per page. Every
page's console errors are reported; the command fails when there are any.
"""

import os
import re
import shutil
import signal
import socket
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

from django.conf import settings
from django.core.management.base import BaseCommand, CommandError, CommandParser

from control.demo import DEMO_PASSWORD, DEMO_USER, wait_for_port

# (file name, path or a callable's key, what to wait for before the shot)
PAGES: list[tuple[str, str, str]] = [
    ("live-map", "/", "main"),
    ("overview", "/overview/", "#vehicle-states"),
    ("vehicles", "/vehicles/", "#vehicles-table"),
    ("vehicle", "<vehicle>", "main"),
    ("orders-board", "/orders/", "#order-board"),
    ("alerts", "/alerts/", "#alerts-table"),
    ("reports", "/reports/", "#traffic-waits"),
    ("traffic-waits", "/reports/#wait-heatmap", "#wait-heatmap"),
    ("layout-editor", "<layout>", "main"),
    ("energy", "/energy/", "main"),
    ("maintenance", "/maintenance/", "main"),
]


# As in tests/browser.py: headless as root, and quiet on a closed network.
CHROMIUM_ARGS = [
    "--no-sandbox",
    "--disable-gpu",
    "--disable-background-networking",
    "--disable-component-update",
    "--no-first-run",
    "--disable-sync",
]


VEHICLE_LINK = r'href="(/vehicles/(?!generated/)[^/"]+/[^/"]+/)"'
LAYOUT_LINK = r'href="(/layouts/\d+/edit/)"'


def free_port() -> int:
    with socket.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        return int(probe.getsockname()[1])


class Command(BaseCommand):
    help = "Start the demo on a temporary database and save screenshots of the main pages."

    def add_arguments(self, parser: CommandParser) -> None:
        parser.add_argument("--out", default=str(Path(settings.BASE_DIR) / "docs" / "screenshots"))
        parser.add_argument("--vehicles", type=int, default=6)
        parser.add_argument("--warm-up", type=float, default=25.0, help="seconds of driving first")
        parser.add_argument("--width", type=int, default=1280)
        parser.add_argument("--height", type=int, default=800)
        parser.add_argument("--chromium", default=shutil.which("chromium") or "/usr/bin/chromium")

    def handle(self, *args: Any, **options: Any) -> None:
        out = Path(options["out"])
        out.mkdir(parents=True, exist_ok=True)
        with tempfile.TemporaryDirectory(prefix="fleet-screens-") as scratch:
            env = self._environment(Path(scratch))
            manage = [sys.executable, str(Path(settings.BASE_DIR) / "manage.py")]
            subprocess.run([*manage, "migrate", "--verbosity", "0"], env=env, check=True)  # noqa: S603
            subprocess.run(  # noqa: S603  (our own manage.py)
                [*manage, "generate_report_history", "--vehicles", "4", "--days", "7"],
                env=env,
                check=True,
                stdout=subprocess.DEVNULL,
            )
            port = free_port()
            demo = subprocess.Popen(  # noqa: S603  (our own manage.py)
                [*manage, "run_demo", "--port", str(port), "--vehicles", str(options["vehicles"])]
                + ["--time-scale", "4"],
                env=env,
                stdout=open(Path(scratch) / "demo.log", "w"),  # noqa: SIM115  (closed with the dir)
                stderr=subprocess.STDOUT,
                start_new_session=True,
            )
            try:
                wait_for_port("127.0.0.1", port, timeout=90)
                time.sleep(options["warm_up"])
                problems = self._shoot(f"http://127.0.0.1:{port}", out, options)
            finally:
                os.killpg(demo.pid, signal.SIGINT)
                try:
                    demo.wait(timeout=20)
                except subprocess.TimeoutExpired:
                    os.killpg(demo.pid, signal.SIGKILL)
        if problems:
            raise CommandError("console errors:\n" + "\n".join(problems))

    def _environment(self, scratch: Path) -> dict[str, str]:
        env = {k: v for k, v in os.environ.items() if k not in {"REDIS_URL", "MQTT_URL"}}
        env |= {
            "DATABASE_URL": f"sqlite:///{scratch / 'demo.sqlite3'}",
            "MQTT_EMBEDDED_PORT": str(free_port()),
            "CONTROL_HEALTH_PORT": "0",
            "CELERY_TASK_ALWAYS_EAGER": "1",
        }
        return env

    def _shoot(self, base: str, out: Path, options: dict[str, Any]) -> list[str]:
        from playwright.sync_api import ConsoleMessage, Error, sync_playwright

        problems: list[str] = []
        with sync_playwright() as playwright:
            browser = playwright.chromium.launch(
                executable_path=options["chromium"], args=CHROMIUM_ARGS
            )
            try:
                page = browser.new_page(
                    viewport={"width": options["width"], "height": options["height"]}
                )
                page.set_default_timeout(20_000)
                current = {"name": ""}

                def on_console(message: ConsoleMessage) -> None:
                    if message.type == "error":
                        problems.append(f"{current['name']}: {message.text}")

                def on_error(error: Error) -> None:
                    problems.append(f"{current['name']}: {error}")

                page.on("console", on_console)
                page.on("pageerror", on_error)
                page.goto(f"{base}/accounts/login/")
                page.fill("#id_username", DEMO_USER)
                page.fill("#id_password", DEMO_PASSWORD)
                page.click("button[type=submit]")
                page.wait_for_load_state("networkidle")
                for name, path, ready in PAGES:
                    current["name"] = name
                    url = self._resolve(page, base, path)
                    if url is None:
                        self.stderr.write(f"skipped {name}: no such page in this demo")
                        continue
                    page.goto(f"{base}{url}")
                    page.wait_for_selector(ready)
                    page.wait_for_timeout(1500)  # live pages draw a few updates first
                    page.screenshot(path=str(out / f"{name}.png"))
                    self.stdout.write(f"saved {out / f'{name}.png'} ({url})")
            finally:
                browser.close()
        return problems

    def _resolve(self, page: Any, base: str, path: str) -> str | None:
        """A concrete URL for the placeholders: the first simulated vehicle, the first layout."""
        if not path.startswith("<"):
            return path
        listing = "/vehicles/" if path == "<vehicle>" else "/layouts/"
        pattern = VEHICLE_LINK if path == "<vehicle>" else LAYOUT_LINK
        page.goto(f"{base}{listing}")
        found = re.search(pattern, page.content())
        return found.group(1) if found else None
