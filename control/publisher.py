"""Master-to-vehicle messages: built with the right header and published on the right topic."""

from collections import Counter
from collections.abc import Callable
from typing import Any

import msgspec

import vda5050
from control.live import LiveVehicle
from control.versions import to_wire
from vda5050 import encode
from vda5050.enums import TopicKind
from vda5050.headers import HeaderCounter, HeaderFields

Publish = Callable[[str, bytes, int], None]


class Publisher:
    """Publishes orders and instant actions with header ids counted per vehicle and topic."""

    def __init__(self, publish: Publish | None, counters: Counter[str]) -> None:
        self.publish: Publish = publish if publish is not None else _discard
        self.headers = HeaderCounter()
        self.counters = counters

    def order(
        self,
        vehicle: LiveVehicle,
        *,
        order_id: str,
        order_update_id: int,
        nodes: list[vda5050.Node],
        edges: list[vda5050.Edge],
    ) -> None:
        """Publish an order (or order update) to `vehicle`."""
        message = vda5050.Order(
            **self._header(vehicle, TopicKind.ORDER),
            order_id=order_id,
            order_update_id=order_update_id,
            nodes=nodes,
            edges=edges,
        )
        self._send(vehicle, TopicKind.ORDER, message)

    def instant_action(
        self,
        vehicle: LiveVehicle,
        action_type: str,
        *,
        action_id: str | None = None,
        parameters: dict[str, Any] | None = None,
    ) -> str:
        """Publish one instant action to `vehicle`; returns its actionId."""
        action = vda5050.make_action(action_type, parameters, action_id=action_id)
        message = vda5050.InstantActions(
            **self._header(vehicle, TopicKind.INSTANT_ACTIONS), actions=[action]
        )
        self._send(vehicle, TopicKind.INSTANT_ACTIONS, message)
        return action.action_id

    def _header(self, vehicle: LiveVehicle, kind: TopicKind) -> HeaderFields:
        return self.headers.header(
            vehicle.manufacturer, vehicle.serial_number, kind, vehicle.version
        )

    def _send(self, vehicle: LiveVehicle, kind: TopicKind, message: Any) -> None:
        topic = vda5050.Topic(
            interface_name=vehicle.interface_name,
            major_version=vda5050.major_version_of(vehicle.version),
            manufacturer=vehicle.manufacturer,
            serial_number=vehicle.serial_number,
            kind=kind,
        )
        self.publish(str(topic), _encode_for(vehicle, kind, message), 0)
        self.counters[f"sent_{kind}"] += 1


def _encode_for(vehicle: LiveVehicle, kind: TopicKind, message: Any) -> bytes:
    """The message as this vehicle's version and stack expect it (docs/DIALECTS.md)."""
    message = to_wire(kind, message, vehicle.version)
    if kind == TopicKind.INSTANT_ACTIONS and vehicle.dialect == "INSTANT_ACTIONS_KEY":
        data = msgspec.json.decode(encode(message))  # encode validates (no NaN, …)
        data["instantActions"] = data.pop("actions")
        return msgspec.json.encode(data)
    return encode(message)


def _discard(topic: str, payload: bytes, qos: int) -> None:
    """The publish function until an MQTT link sets the real one."""
