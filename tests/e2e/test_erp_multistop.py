"""Issue 5 acceptance, end to end: an ERP client posts multi-stop orders over HTTP, receives a
signed webhook callback for every state change, and every order ends FINISHED on simulated
vehicles (control, a Celery worker and the simulator run as processes on PostgreSQL, Redis and
Mosquitto; the API is served by pytest-django's live server)."""

import json
import time
import urllib.error
import urllib.request
import uuid
from collections import defaultdict
from pathlib import Path
from typing import Any

import pytest

from maps.demo import warehouse_layout
from maps.services import create_layout
from orders import services
from orders.models import TransportOrder
from orders.signing import verify
from robots.models import Vehicle
from tests.e2e.conftest import start_fleet
from tests.e2e.processes import wait_until
from tests.orders.webhook_server import webhook_endpoint

pytestmark = [pytest.mark.e2e, pytest.mark.django_db(transaction=True)]

ORDERS = [
    # pick, a custom action (the simulator's stopCharging always succeeds), drop
    [("PICK-1", "PICK", ""), ("PICK-3", "ACTION", "stopCharging"), ("DROP-2", "DROP", "")],
    # two loads one after the other
    [
        ("PICK-2", "PICK", ""),
        ("DROP-1", "DROP", ""),
        ("PICK-4", "PICK", ""),
        ("DROP-3", "DROP", ""),
    ],
    [("PICK-5", "PICK", ""), ("DROP-5", "DROP", "")],
    [("PICK-6", "PICK", ""), ("PICK-1", "ACTION", "stopCharging"), ("DROP-6", "DROP", "")],
]


def post(url: str, token: str, body: dict[str, Any]) -> dict[str, Any]:
    request = urllib.request.Request(
        url,
        data=json.dumps(body).encode(),
        method="POST",
        headers={
            "Authorization": f"Bearer {token}",
            "Content-Type": "application/json",
            "Idempotency-Key": str(uuid.uuid4()),
        },
    )
    try:
        with urllib.request.urlopen(request, timeout=30) as response:
            assert response.status == 201
            return json.loads(response.read())
    except urllib.error.HTTPError as error:
        raise AssertionError(f"{error.code}: {error.read()!r}") from None


def test_erp_multi_stop_orders_finish_with_signed_callbacks_for_every_change(
    fleet_env: dict[str, str], tmp_path: Path, live_server: Any
) -> None:
    layout = create_layout(spec=warehouse_layout(columns=8, rows=4))  # PICK-1..6, DROP-1..6
    erp = services.create_integration_client(name="erp", scopes=["orders:read", "orders:write"])
    token = services.issue_api_token(client=erp)[1]
    with webhook_endpoint() as endpoint:
        subscription = services.create_webhook_subscription(
            client=erp, url=endpoint.url, events=["order.*", "vehicle.order_finished"]
        )
        processes = start_fleet(fleet_env, tmp_path, layout, vehicles=3)
        try:
            wait_until(
                lambda: Vehicle.objects.filter(connection="ONLINE").count() == 3,
                60,
                "3 vehicles registered online",
                processes,
            )
            started = time.monotonic()
            created = [
                post(
                    f"{live_server.url}/api/v1/orders/",
                    token,
                    {
                        "steps": [
                            {"station": s, "operation": o, **({"action_type": a} if a else {})}
                            for s, o, a in steps
                        ],
                        "external_ref": f"ERP-{i}",
                        "load_id": f"LOAD-{i}",
                    },
                )
                for i, steps in enumerate(ORDERS)
            ]
            ids = [order["id"] for order in created]
            wait_until(
                lambda: (
                    not TransportOrder.objects.filter(
                        pk__in=ids, status__in=TransportOrder.OPEN_STATUSES
                    ).exists()
                ),
                300,
                "all orders closed",
                processes,
            )
            duration = time.monotonic() - started

            def all_callbacks() -> bool:
                finished = [r for r in endpoint.received if b'"order.finished"' in r.body]
                return len(finished) >= len(ids)

            wait_until(all_callbacks, 60, "a finished callback per order", processes)
            time.sleep(2)  # late deliveries of the same flush
        finally:
            codes = {p.name: p.terminate() for p in processes}

    orders = {o.pk: o for o in TransportOrder.objects.filter(pk__in=ids)}
    assert {o.status for o in orders.values()} == {"FINISHED"}, {
        pk: (o.status, o.failure_reason) for pk, o in orders.items()
    }
    assert codes == {"control": 0, "worker": 0, "simulator": 0}, codes
    callbacks: dict[int, list[str]] = defaultdict(list)
    for received in endpoint.received:
        assert verify(subscription.secret, received.body, received.headers["X-Fleet-Signature"])
        body = json.loads(received.body)
        if body["type"].startswith("order."):
            callbacks[body["data"]["order"]["id"]].append(body["type"])
    for spec, pk in zip(ORDERS, ids, strict=True):
        order = orders[pk]
        timeline = [f"order.{kind.lower()}" for kind in order.events.values_list("kind", flat=True)]
        # Every timeline entry was called back once (delivery order may differ under retries).
        assert sorted(callbacks[pk]) == sorted(timeline), (pk, callbacks[pk], timeline)
        assert timeline[:3] == ["order.created", "order.assigned", "order.started"]
        assert timeline[-1] == "order.finished"
        assert timeline.count("order.step_reached") == len(spec)
        steps = list(order.steps.order_by("index"))
        assert all(step.finished_at is not None for step in steps), pk
        assert [s.vda_action_type for s in steps] == [a or o.lower() for _, o, a in spec]
        reached = list(order.events.filter(kind="STEP_REACHED").order_by("at", "pk"))
        assert [e.detail["index"] for e in reached] == list(range(len(spec))), pk
        # Each step's action was done at its own station's node.
        assert [e.detail["node"] for e in reached] == [s.station.node.node_id for s in steps], (
            pk,
            [e.detail for e in reached],
        )
    vehicle_finished = [r for r in endpoint.received if b'"vehicle.order_finished"' in r.body]
    assert len(vehicle_finished) == len(ids)
    print(f"e2e ERP: {len(ids)} multi-stop orders finished by 3 vehicles in {duration:.1f} s")
