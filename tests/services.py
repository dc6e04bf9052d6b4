"""Which backing services the test run uses: the real ones when they answer, else stand-ins.

`make test` prints the choice. With FLEET_REQUIRE_SERVICES=1 (CI) a missing service is an error,
so CI can never pass by silently falling back to SQLite, in-memory layers or the embedded broker.
"""

import os
import socket
from urllib.parse import urlsplit

DEFAULTS = {
    "DATABASE_URL": "postgres://postgres@127.0.0.1:5432/fleet",
    "REDIS_URL": "redis://127.0.0.1:6379/15",
    "MQTT_URL": "mqtt://127.0.0.1:1883",
}


def answers(url: str, timeout: float = 0.5) -> bool:
    """Whether something accepts TCP connections at the URL's host and port."""
    parts = urlsplit(url)
    try:
        with socket.create_connection((parts.hostname or "127.0.0.1", parts.port or 0), timeout):
            return True
    except OSError:
        return False


def choose() -> dict[str, str]:
    """Set DATABASE_URL/REDIS_URL/MQTT_URL for the real services that answer; return the choice."""
    required = os.environ.get("FLEET_REQUIRE_SERVICES") == "1"
    chosen: dict[str, str] = {}
    for name, default in DEFAULTS.items():
        url = os.environ.get(f"TEST_{name}", os.environ.get(name, default))
        if answers(url):
            os.environ[name] = url
            chosen[name] = url
        elif required:
            raise RuntimeError(f"FLEET_REQUIRE_SERVICES=1 but {name} ({url}) does not answer")
        else:
            os.environ.pop(name, None)
            chosen[name] = "embedded stand-in"
    return chosen
