"""End to end on the real services: control, a Celery worker and 3 simulated vehicles as processes
against Mosquitto, PostgreSQL and Redis; 5 transport orders must all finish."""

import json
import os
import time
import uuid
from pathlib import Path

import pytest
from django.conf import settings

from maps.demo import warehouse_layout
from maps.models import Station
from maps.selectors import layout_as_dict
from maps.services import create_layout
from orders.models import OrderEvent, TransportOrder
from orders.services import create_transport_order
from robots.models import Vehicle
from tests.e2e.processes import Process, python, wait_until

pytestmark = [pytest.mark.e2e, pytest.mark.django_db(transaction=True)]

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


@pytest.mark.parametrize("version", ["2.0.0", "2.1.0"])
def test_five_orders_finish_with_three_vehicles(
    fleet_env: dict[str, str], tmp_path: Path, version: str
) -> None:
    layout = create_layout(spec=warehouse_layout(columns=6, rows=4))
    layout_file = tmp_path / "layout.json"
    layout_file.write_text(json.dumps(layout_as_dict(map=layout)))
    processes = [
        Process("control", python("manage.py", "run_control"), fleet_env, tmp_path),
        Process(
            "worker",
            python("-m", "celery", "-A", "fleet", "worker", "--pool", "solo", "--loglevel", "INFO"),
            fleet_env,
            tmp_path,
        ),
        Process(
            "simulator",
            python(
                "-m",
                "simulator",
                "--count",
                "3",
                "--layout",
                str(layout_file),
                "--broker",
                fleet_env["MQTT_URL"],
                "--interface",
                fleet_env["VDA5050_INTERFACE"],
                "--time-scale",
                "10",
                "--version",
                version,
            ),
            fleet_env,
            tmp_path,
        ),
    ]
    started = time.monotonic()
    try:
        wait_until(
            lambda: Vehicle.objects.filter(connection="ONLINE").count() == 3,
            60,
            "3 vehicles registered online",
            processes,
        )
        picks = list(Station.objects.filter(map=layout, kind=Station.Kind.PICK))
        drops = list(Station.objects.filter(map=layout, kind=Station.Kind.DROP))
        orders = [
            create_transport_order(
                source=picks[i % len(picks)],
                destination=drops[-1 - i % len(drops)],
                load_id=f"LOAD-{i}",
            )
            for i in range(5)
        ]

        wait_until(
            lambda: (
                not TransportOrder.objects.filter(status__in=TransportOrder.OPEN_STATUSES).exists()
            ),
            240,
            "all orders closed",
            processes,
        )
        duration = time.monotonic() - started
    finally:
        codes = {p.name: p.terminate() for p in processes}

    statuses = {
        o.pk: o.status for o in TransportOrder.objects.filter(pk__in=[o.pk for o in orders])
    }
    assert set(statuses.values()) == {"FINISHED"}, statuses
    assert codes == {"control": 0, "worker": 0, "simulator": 0}, codes
    for order in TransportOrder.objects.filter(pk__in=statuses).select_related("destination__node"):
        kinds = list(order.events.values_list("kind", flat=True))
        assert kinds == [
            "CREATED",
            "ASSIGNED",
            "STARTED",
            "STEP_REACHED",
            "STEP_REACHED",
            "FINISHED",
        ], (order.pk, kinds)
        steps = [e.detail["step"] for e in order.events.filter(kind=OrderEvent.Kind.STEP_REACHED)]
        assert steps == ["pick", "drop"]
    for vehicle in Vehicle.objects.all():
        last = vehicle.transport_orders.filter(status="FINISHED").order_by("-finished_at").first()
        if last is not None:
            assert vehicle.last_node_id == last.destination.node.node_id, vehicle
        assert vehicle.errors == [], vehicle.errors
    assert set(Vehicle.objects.values_list("protocol_version", flat=True)) == {version}
    print(f"e2e {version}: 5 orders finished by 3 vehicles in {duration:.1f} s")
