"""The split-brain row's view of the two controls: each one's `/ready` answer, polled."""

import json
import threading
import time
import urllib.error
import urllib.request
from collections.abc import Callable
from typing import Any

from bench.faults.fleet import Fleet, wait_until


class HealthWatch(threading.Thread):
    """Polls each control's `/ready` every 0.1 s; keeps the latest answer per control."""

    def __init__(self, ports: dict[str, int]) -> None:
        super().__init__(daemon=True)
        self.ports = ports
        self.latest: dict[str, dict[str, Any]] = {}
        self._halt = threading.Event()

    def run(self) -> None:
        while not self._halt.wait(0.1):
            for name, port in self.ports.items():
                self.latest[name] = {**_ready(port), "at": time.monotonic()}

    def ready_leader(self) -> tuple[str, int] | None:
        """(control name, fencing) of the control that answers ready, if one does."""
        for name, answer in self.latest.items():
            if answer.get("ready"):
                return name, int(answer.get("fencing") or 0)
        return None

    def role(self, name: str) -> str | None:
        return self.latest.get(name, {}).get("role")

    def wait(
        self, condition: Callable[[], object], timeout: float, message: str, fleet: Fleet | None
    ) -> float:
        """`wait_until`, with each control's last answer in the error (what a failed CI shows)."""
        try:
            return wait_until(condition, timeout, message, fleet)
        except TimeoutError as error:
            raise TimeoutError(f"{error}; last answers: {self.latest}") from None

    def wait_settled(self, names: list[str], timeout: float, fleet: Fleet) -> tuple[str, int]:
        """Wait until one reading shows a ready leader and every other control on standby;
        (leader, fencing). Judged on one reading: the leader may change on its own (a starved
        renewal thread steps down), so "the others" are whoever does not lead at that moment."""
        found: list[tuple[str, int]] = []

        def settled() -> bool:
            now = self.ready_leader()
            if now is None or any(self.role(n) != "standby" for n in names if n != now[0]):
                return False
            found[:] = [now]
            return True

        self.wait(settled, timeout, "a ready leader and the rest standby", fleet)
        return found[0]

    def stop(self) -> None:
        self._halt.set()


def _ready(port: int) -> dict[str, Any]:
    try:
        with urllib.request.urlopen(f"http://127.0.0.1:{port}/ready", timeout=0.5) as response:  # noqa: S310
            return dict(json.loads(response.read()))
    except urllib.error.HTTPError as error:
        return dict(json.loads(error.read()))
    except (OSError, ValueError):
        return {"role": None, "ready": False}  # not answering: dead, frozen or starting
