"""The live page in headless Chromium for `bench.live_map`: logged in, with its counters."""

import time
from typing import Any

USER, PASSWORD = "bench", "bench-live-map-password"


class Page:
    """The live page in headless Chromium, logged in, with its counters."""

    def __init__(self, playwright: Any, port: int) -> None:
        from tests.browser import CHROMIUM, CHROMIUM_ARGS

        base = f"http://127.0.0.1:{port}"
        self.browser = playwright.chromium.launch(executable_path=CHROMIUM, args=CHROMIUM_ARGS)
        self.page = self.browser.new_page(viewport={"width": 1440, "height": 900})
        self.errors: list[str] = []  # a console error is a failure
        self.page.on("console", lambda m: self.errors.append(m.text) if m.type == "error" else None)
        self.page.on("pageerror", lambda e: self.errors.append(str(e)))
        self.page.on(
            "response",
            lambda r: self.errors.append(f"HTTP {r.status} {r.url}") if r.status >= 400 else None,
        )
        self.page.goto(f"{base}/admin/login/?next=/")
        self.page.fill("#id_username", USER)
        self.page.fill("#id_password", PASSWORD)
        self.page.click("input[type=submit]")
        self.page.wait_for_url(f"{base}/")
        self.page.wait_for_selector('#connection[data-state="live"]', timeout=30_000)
        self.errors.clear()  # only the live page's own (the login page has no favicon link)
        self.cdp = self.page.context.new_cdp_session(self.page)
        self.cdp.send("Performance.enable")

    def cpu_seconds(self) -> dict[str, float]:
        """CPU seconds so far of the page's main thread and of its whole renderer process."""
        metrics = {
            m["name"]: m["value"] for m in self.cdp.send("Performance.getMetrics")["metrics"]
        }
        return {
            "thread": metrics.get("ThreadTime", 0.0),
            "process": metrics.get("ProcessTime", 0.0),
        }

    def wait_for_vehicles(self, count: int) -> None:
        self.page.wait_for_function(
            f"() => window.fleetMap.vehicleCount() >= {count}", timeout=120_000
        )

    def measure(self, seconds: float, prefix: str) -> dict[str, Any]:
        """Frames and snapshots per second over `seconds`, and the slowest whole second."""
        stats = "() => window.fleetMap.stats()"
        self.page.evaluate("() => window.fleetMap.resetStats()")
        fps, snapshots = [], []
        cpu_before = self.cpu_seconds()
        last = self.page.evaluate(stats)
        for _ in range(max(1, int(seconds))):
            time.sleep(1.0)
            now = self.page.evaluate(stats)
            span = now["seconds"] - last["seconds"]
            fps.append((now["frames"] - last["frames"]) / span)
            snapshots.append((now["snapshots"] - last["snapshots"]) / span)
            last = now
        return {
            f"{prefix}_fps_mean": round(last["frames"] / last["seconds"], 1),
            f"{prefix}_fps_min_1s": round(min(fps), 1),
            f"{prefix}_snapshots_per_s_mean": round(last["snapshots"] / last["seconds"], 2),
            f"{prefix}_snapshots_per_s_min_1s": round(min(snapshots), 1),
            f"{prefix}_draw_ms_mean": round(last["drawMs"] / max(1, last["frames"]), 2),
            # websocket message handling: JSON.parse and merging the rows
            f"{prefix}_message_ms_mean": round(last["messageMs"] / max(1, last["snapshots"]), 2),
            f"{prefix}_rows_per_s": round(last["rows"] / last["seconds"]),
            f"{prefix}_bytes_per_s": round(last["bytes"] / last["seconds"]),
            f"{prefix}_seconds": round(last["seconds"], 1),
            # CPU the page used per second: what it needs, whatever the machine's load
            f"{prefix}_main_thread_cpu_per_s": round(
                (self.cpu_seconds()["thread"] - cpu_before["thread"]) / last["seconds"], 3
            ),
            f"{prefix}_renderer_cpu_per_s": round(
                (self.cpu_seconds()["process"] - cpu_before["process"]) / last["seconds"], 3
            ),
        }

    def close(self) -> None:
        self.page.screenshot(path="/tmp/live_map_bench.png")  # to look at; not kept
        self.browser.close()
