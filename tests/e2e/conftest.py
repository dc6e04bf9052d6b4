"""Fixtures for end-to-end tests that start the fleet's real processes."""

import json
import os
import uuid
from pathlib import Path

import pytest
from django.conf import settings

from maps.models import Map
from maps.selectors import layout_as_dict
from tests.e2e.processes import Process, python

REAL = {name: settings.SERVICES.get(name, "") for name in ("DATABASE_URL", "REDIS_URL", "MQTT_URL")}


@pytest.fixture
def fleet_env(tmp_path: Path) -> dict[str, str]:
    if any(not url.startswith(("postgres", "redis", "mqtt")) for url in REAL.values()):
        pytest.skip(f"needs PostgreSQL, Redis and Mosquitto; have {REAL}")
    db = settings.DATABASES["default"]
    env = {key: value for key, value in os.environ.items() if not key.startswith("PYTEST")}
    env.update(
        {
            "DJANGO_SETTINGS_MODULE": "fleet.settings",
            "DATABASE_URL": f"postgres://{db['USER']}@{db['HOST']}:{db['PORT']}/{db['NAME']}",
            "REDIS_URL": REAL["REDIS_URL"],
            "MQTT_URL": REAL["MQTT_URL"],
            "VDA5050_INTERFACE": f"e2e{uuid.uuid4().hex[:8]}",  # no crosstalk with other runs
            "CELERY_TASK_ALWAYS_EAGER": "0",
            "FLEET_FLUSH_INTERVAL": "0.5",
        }
    )
    return env


def start_fleet(
    env: dict[str, str],
    log_dir: Path,
    layout: Map,
    *,
    vehicles: int,
    version: str = "2.0.0",
    extra: tuple[str, ...] = (),
) -> list[Process]:
    """control, a Celery worker and `vehicles` simulated vehicles, as processes."""
    layout_file = log_dir / "layout.json"
    layout_file.write_text(json.dumps(layout_as_dict(map=layout)))
    return [
        Process("control", python("manage.py", "run_control"), env, log_dir),
        Process(
            "worker",
            python("-m", "celery", "-A", "fleet", "worker", "--pool", "solo", "--loglevel", "INFO"),
            env,
            log_dir,
        ),
        Process(
            "simulator",
            python(
                "-m",
                "simulator",
                "--count",
                str(vehicles),
                "--layout",
                str(layout_file),
                "--broker",
                env["MQTT_URL"],
                "--interface",
                env["VDA5050_INTERFACE"],
                "--time-scale",
                "10",
                "--version",
                version,
                *extra,
            ),
            env,
            log_dir,
        ),
    ]
