"""Master-to-vehicle messages: built with the right header and published on the right topic.

Before a message goes out it is checked against the vehicle's string limits (REFERENCE J.44,
`control.limits`); one that does not fit raises ProtocolLimitError and is not sent, and its
headerId is given back so the vehicle sees no gap. Order actions go out `retriable` to 3.0
vehicles whose factsheet takes retry and skipRetry (E.27, `control.action_states`).
"""

import uuid
from collections import Counter
from collections.abc import Callable, Collection
from typing import Any

import msgspec

import vda5050
from control.limits import ProtocolLimitError, check_message
from control.live import LiveVehicle
from control.message_log import OUT, MessageLog
from control.versions import to_wire
from vda5050 import encode, v3
from vda5050.enums import TopicKind
from vda5050.headers import HeaderCounter, HeaderFields

Publish = Callable[[str, bytes, int], None]

__all__ = ["ProtocolLimitError", "Publish", "Publisher"]

SENT_INSTANT_KEPT = 500  # instant action ids remembered per vehicle (3.0 clearing, E.28)


class Publisher:
    """Publishes orders and instant actions with header ids counted per vehicle and topic."""

    def __init__(
        self, publish: Publish | None, counters: Counter[str], messages: MessageLog | None = None
    ) -> None:
        self.publish: Publish = publish if publish is not None else _discard
        # The fence of a standby pair (control.leader): asked right before each message goes out.
        self.may_publish: Callable[[], bool] = _always
        self.headers = HeaderCounter()
        self.counters = counters
        self.messages = messages  # the vehicle page's log of what we sent

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
        self._send(vehicle, TopicKind.ORDER, message, retriable=_retriable(vehicle, nodes, edges))

    def instant_action(
        self,
        vehicle: LiveVehicle,
        action_type: str,
        *,
        action_id: str | None = None,
        parameters: dict[str, Any] | None = None,
    ) -> str:
        """Publish one instant action to `vehicle`; returns its actionId."""
        if action_id is None:
            action_id = _fresh_id(vehicle)
        action = vda5050.make_action(action_type, parameters, action_id=action_id)
        message = vda5050.InstantActions(
            **self._header(vehicle, TopicKind.INSTANT_ACTIONS), actions=[action]
        )
        self._send(vehicle, TopicKind.INSTANT_ACTIONS, message)
        vehicle.sent_instant[action.action_id] = None
        while len(vehicle.sent_instant) > SENT_INSTANT_KEPT:
            del vehicle.sent_instant[next(iter(vehicle.sent_instant))]
        return action.action_id

    def zone_set(self, vehicle: LiveVehicle, zone_set: v3.ZoneSetDefinition) -> None:
        """Publish a 3.0 zone set on the vehicle's `zoneSet` topic (REFERENCE L.48)."""
        message = v3.ZoneSet(**self._header(vehicle, TopicKind.ZONE_SET), zone_set=zone_set)
        self._send(vehicle, TopicKind.ZONE_SET, message)

    def responses(self, vehicle: LiveVehicle, responses: list[v3.Response]) -> None:
        """Publish answers to 3.0 zone/edge requests on `responses` (REFERENCE L.49)."""
        message = v3.Responses(**self._header(vehicle, TopicKind.RESPONSES), responses=responses)
        self._send(vehicle, TopicKind.RESPONSES, message)

    def _header(self, vehicle: LiveVehicle, kind: TopicKind) -> HeaderFields:
        return self.headers.header(
            vehicle.manufacturer, vehicle.serial_number, kind, vehicle.version
        )

    def _send(
        self,
        vehicle: LiveVehicle,
        kind: TopicKind,
        message: Any,
        *,
        retriable: Collection[str] = (),
    ) -> None:
        topic = str(
            vda5050.Topic(
                interface_name=vehicle.interface_name,
                major_version=vda5050.major_version_of(vehicle.version),
                manufacturer=vehicle.manufacturer,
                serial_number=vehicle.serial_number,
                kind=kind,
            )
        )
        payload = _encode_for(vehicle, kind, message, retriable)
        if vehicle.capabilities is not None:
            try:
                check_message(vehicle.capabilities.strings, topic, payload)
            except ProtocolLimitError:
                # Not sent: the next message must carry this headerId (no gap for the vehicle).
                self.headers.set_next(
                    vehicle.manufacturer, vehicle.serial_number, kind, message.header_id
                )
                self.counters["limit_refused"] += 1
                raise
        if not self.may_publish():
            # Lease expired (frozen, database lost, or another process leads): sent by no one;
            # identical resends or the next leader's adoption cover what is lost.
            self.counters["publish_fenced"] += 1
            return
        self.publish(topic, payload, 0)
        self.counters[f"sent_{kind}"] += 1
        if self.messages is not None:
            self.messages.record(vehicle.key, OUT, kind, payload)


def _fresh_id(vehicle: LiveVehicle) -> str:
    """A new unique actionId that fits the vehicle's idLen and idNumericalOnly (J.44)."""
    fresh = uuid.uuid4()
    strings = vehicle.capabilities.strings if vehicle.capabilities is not None else None
    if strings is None:
        return str(fresh)  # the spec's suggestion
    text = str(fresh.int) if strings.id_numerical_only else fresh.hex
    return text[: strings.id_len] if strings.id_len else text


def _retriable(
    vehicle: LiveVehicle, nodes: list[vda5050.Node], edges: list[vda5050.Edge]
) -> frozenset[str]:
    """Ids of the order actions to send `retriable` (3.0 vehicles that take retry/skipRetry)."""
    capabilities = vehicle.capabilities
    if vda5050.major_version_of(vehicle.version) != "v3" or capabilities is None:
        return frozenset()
    if not capabilities.retries_actions:
        return frozenset()
    actions = [a for n in nodes for a in n.actions] + [a for e in edges for a in e.actions]
    return frozenset(a.action_id for a in actions)


def _encode_for(
    vehicle: LiveVehicle, kind: TopicKind, message: Any, retriable: Collection[str] = ()
) -> bytes:
    """The message as this vehicle's version and stack expect it (docs/DIALECTS.md)."""
    message = to_wire(kind, message, vehicle.version, retriable=retriable)
    if kind == TopicKind.INSTANT_ACTIONS and vehicle.dialect == "INSTANT_ACTIONS_KEY":
        data = msgspec.json.decode(encode(message))  # encode validates (no NaN, …)
        data["instantActions"] = data.pop("actions")
        return msgspec.json.encode(data)
    return encode(message)


def _always() -> bool:
    return True


def _discard(topic: str, payload: bytes, qos: int) -> None:
    """The publish function until an MQTT link sets the real one."""
