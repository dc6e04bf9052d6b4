"""Per-vehicle protocol versions at the edge: 3.0 vehicles are adapted onto the 2.x model.

`control` keeps one model (the 2.x Structs). Inbound 3.0 messages are adapted on decode, outbound
orders and instant actions on publish (REFERENCE §6, `vda5050.adapt`). The wire version comes from
the topic's major level: a vehicle that changes firmware changes its topics too.
"""

import functools
from collections.abc import Callable, Collection
from typing import Any

import vda5050
from vda5050 import adapt, v3
from vda5050.enums import TopicKind

_INBOUND: dict[str, Callable[[Any], Any]] = {
    TopicKind.STATE: adapt.state_v3_to_v2,
    TopicKind.FACTSHEET: adapt.factsheet_v3_to_v2,
    TopicKind.CONNECTION: adapt.connection_v3_to_v2,
    TopicKind.VISUALIZATION: adapt.visualization_v3_to_v2,
}


@functools.lru_cache(maxsize=256)  # once per message: a handful of distinct pairs per fleet
def wire_version(topic_major: str, known: str | None) -> str:
    """The version to decode with: the vehicle's, unless its topic says another major (or
    the one known is malformed: stored before the decoder refused such headers)."""
    try:
        if known is not None and vda5050.major_version_of(known) == topic_major:
            return known
    except vda5050.VersionError:
        pass
    return "3.0.0" if topic_major == "v3" else "2.0.0"


# Decoded messages are of these exact types (a set lookup: isinstance with a union took
# half a microsecond per message).
_V3_INBOUND_TYPES = frozenset({v3.State, v3.Factsheet, v3.Connection, v3.Visualization})


def to_model(kind: str, message: Any) -> Any:
    """An inbound message as the 2.x Struct the master works with."""
    if type(message) in _V3_INBOUND_TYPES:
        return _INBOUND[kind](message)
    return message


def to_wire(kind: str, message: Any, version: str, *, retriable: Collection[str] = ()) -> Any:
    """An outbound 2.x order or instant actions in the vehicle's version; order actions whose
    ids are in `retriable` go out with `retriable: true` (3.0 only, REFERENCE E.27)."""
    if vda5050.major_version_of(version) != "v3":
        return message
    if kind == TopicKind.ORDER:
        return adapt.order_v2_to_v3(message, version=version, retriable=retriable)
    if kind == TopicKind.INSTANT_ACTIONS:
        return adapt.instant_actions_v2_to_v3(message, version=version)
    return message
