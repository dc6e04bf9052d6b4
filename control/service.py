"""Wires a ControlLoop from the settings: broker, store, command queue and broadcasts."""

from typing import Any

from django.conf import settings

from control.controller import Controller
from control.persistence import DjangoStore
from control.runner import ControlLoop, MqttLink
from fleet.control_queue import receive_commands
from fleet.mqtt import make_client
from fleet.realtime import LIVE_GROUP, broadcast


def build_control_loop() -> ControlLoop:
    """The control loop for the configured broker and interface (not yet running)."""
    controller = Controller(
        store=DjangoStore(),
        interface_name=settings.VDA5050_INTERFACE,
        base_ahead=settings.FLEET_CONTROL["BASE_AHEAD"] or None,
        traffic=settings.FLEET_CONTROL["TRAFFIC"],
    )
    client, address = make_client(settings.MQTT_URL, client_id_prefix="fleet-control")
    link = MqttLink(client, address.host, address.port, controller)
    return ControlLoop(
        controller,
        link,
        receive_commands=receive_commands,
        broadcast=_broadcast_vehicles,
        intervals=settings.FLEET_CONTROL,
    )


def _broadcast_vehicles(rows: list[dict[str, Any]]) -> None:
    broadcast(LIVE_GROUP, "vehicles.update", {"vehicles": rows})
