"""End to end with one vehicle: a cancelled order ends CANCELLED and the next one runs; a vehicle
whose process freezes mid-order resumes its route without being sent a second order."""

import json
import os
import signal
import threading
import time
from pathlib import Path

import paho.mqtt.client as mqtt
import pytest
from paho.mqtt.enums import CallbackAPIVersion

from fleet.mqtt import BrokerAddress
from maps.demo import warehouse_layout
from maps.models import Station
from maps.services import create_layout
from orders.models import TransportOrder
from orders.services import cancel_transport_order, create_transport_order
from robots.models import Vehicle
from tests.e2e.conftest import start_fleet
from tests.e2e.processes import Process, wait_until

pytestmark = [pytest.mark.e2e, pytest.mark.django_db(transaction=True)]


class OrderSniffer:
    """Records every order message the master publishes on the interface."""

    def __init__(self, url: str, interface: str) -> None:
        self.messages: list[dict] = []
        self._lock = threading.Lock()
        address = BrokerAddress.from_url(url)
        self.client = mqtt.Client(callback_api_version=CallbackAPIVersion.VERSION2)
        self.client.on_message = self._on_message
        self.client.connect(address.host, address.port)
        self.client.subscribe(f"{interface}/+/+/+/order")  # v2 and v3 topics
        self.client.loop_start()

    def _on_message(self, client: mqtt.Client, userdata: object, msg: mqtt.MQTTMessage) -> None:
        with self._lock:
            self.messages.append(json.loads(msg.payload))

    def order_ids(self) -> list[str]:
        with self._lock:
            return [m["orderId"] for m in self.messages]

    def stop(self) -> None:
        self.client.loop_stop()
        self.client.disconnect()


def status(order: TransportOrder) -> str:
    order.refresh_from_db()
    return order.status


VERSIONS = pytest.mark.parametrize("version", ["2.0.0", "2.1.0", "3.0.0"])


@VERSIONS
def test_cancel_then_next_order_then_freeze_and_resume(
    fleet_env: dict[str, str], tmp_path: Path, stop_all: list[Process], version: str
) -> None:
    layout = create_layout(spec=warehouse_layout(columns=6, rows=4))
    sniffer = OrderSniffer(fleet_env["MQTT_URL"], fleet_env["VDA5050_INTERFACE"])
    stop_all.extend(start_fleet(fleet_env, tmp_path, layout, vehicles=1, version=version))
    simulator = stop_all[-1]
    wait_until(lambda: Vehicle.objects.filter(connection="ONLINE").exists(), 60, "online", stop_all)
    pick = Station.objects.get(map=layout, station_id="PICK-1")
    drop = Station.objects.get(map=layout, station_id="DROP-4")

    first = create_transport_order(source=pick, destination=drop, load_id="A")
    wait_until(lambda: status(first) == "IN_PROGRESS", 60, "first order started", stop_all)
    cancel_transport_order(order=first, reason="wrong pallet")
    wait_until(lambda: status(first) == "CANCELLED", 60, "first order cancelled", stop_all)

    second = create_transport_order(source=pick, destination=drop, load_id="B")
    wait_until(lambda: status(second) == "IN_PROGRESS", 60, "second order started", stop_all)
    os.kill(simulator.popen.pid, signal.SIGSTOP)  # the vehicle goes quiet mid-order ...
    time.sleep(3)
    os.kill(simulator.popen.pid, signal.SIGCONT)  # ... and comes back where it was
    wait_until(lambda: status(second) == "FINISHED", 90, "second order finished", stop_all)
    sniffer.stop()

    vehicle = Vehicle.objects.get()
    assert vehicle.last_node_id == drop.node.node_id
    assert vehicle.errors == []
    assert list(first.events.values_list("kind", flat=True))[-2:] == [
        "CANCEL_REQUESTED",
        "CANCELLED",
    ]
    # One orderId per transport order: the frozen vehicle got updates, never a second order.
    assert set(sniffer.order_ids()) == {f"TO-{first.pk}", f"TO-{second.pk}"}
    updates = [m["orderUpdateId"] for m in sniffer.messages if m["orderId"] == f"TO-{second.pk}"]
    assert updates == sorted(updates)


@VERSIONS
def test_a_rejected_order_fails_with_the_vehicle_reason_and_the_next_one_runs(
    fleet_env: dict[str, str], tmp_path: Path, stop_all: list[Process], version: str
) -> None:
    layout = create_layout(spec=warehouse_layout(columns=6, rows=4))
    stop_all.extend(
        start_fleet(
            fleet_env,
            tmp_path,
            layout,
            vehicles=1,
            version=version,
            extra=("--misbehave", "AGV-1:reject_orders=orderError,reject_count=1"),
        )
    )
    wait_until(lambda: Vehicle.objects.filter(connection="ONLINE").exists(), 60, "online", stop_all)
    pick = Station.objects.get(map=layout, station_id="PICK-2")
    drop = Station.objects.get(map=layout, station_id="DROP-1")

    rejected = create_transport_order(source=pick, destination=drop)
    wait_until(lambda: status(rejected) == "FAILED", 60, "rejected order failed", stop_all)
    accepted = create_transport_order(source=pick, destination=drop)
    wait_until(lambda: status(accepted) == "FINISHED", 90, "next order finished", stop_all)

    expected = "INVALID_ORDER_ACTION" if version.startswith("3.") else "orderError"  # 3.0 name
    assert rejected.failure_reason.startswith(f"rejected by vehicle: {expected}")
