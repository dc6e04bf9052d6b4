"""Structs of the ``zoneSet`` topic (fleet control → robot), 3.0.0 (REFERENCE §3 L.48).

Field names follow the 3.0.0-main schema (``directedLimitation``, ``bidirectedLimitation``,
``priorityFactor``); the type-specific fields of a zone are optional here and required by
the schema only for their zone type (e.g. ``maximumSpeed`` for SPEED_LIMIT).
"""

from __future__ import annotations

from vda5050.v2.base import HeaderId, VDAStruct
from vda5050.v2.order import ActionParameter
from vda5050.v3.enums import (
    BidirectedLimitation,
    BlockingType,
    DirectedLimitation,
    ZoneReleaseLossBehavior,
    ZoneType,
)

__all__ = ["Vertex", "Zone", "ZoneAction", "ZoneSet", "ZoneSetDefinition"]


class Vertex(VDAStruct, kw_only=True):
    """A polygon vertex in metres (zones and factsheet envelopes)."""

    x: float
    y: float


class ZoneAction(VDAStruct, kw_only=True):
    """An action of an ACTION zone (entry, during or exit); zone actions carry no actionId."""

    action_type: str
    action_descriptor: str | None = None
    blocking_type: BlockingType
    action_parameters: list[ActionParameter] | None = None
    retriable: bool | None = None


class Zone(VDAStruct, kw_only=True):
    """One zone: at least three counter-clockwise vertices of a simple polygon."""

    zone_id: str
    zone_type: ZoneType
    zone_descriptor: str | None = None
    vertices: list[Vertex]
    release_loss_behavior: ZoneReleaseLossBehavior | None = None
    maximum_speed: float | None = None
    entry_actions: list[ZoneAction] | None = None
    during_actions: list[ZoneAction] | None = None
    exit_actions: list[ZoneAction] | None = None
    priority_factor: float | None = None
    penalty_factor: float | None = None
    direction: float | None = None
    directed_limitation: DirectedLimitation | None = None
    bidirected_limitation: BidirectedLimitation | None = None


class ZoneSetDefinition(VDAStruct, kw_only=True):
    """The zone set carried by a ``zoneSet`` message (immutable per ``zoneSetId``)."""

    map_id: str
    zone_set_id: str
    zone_set_descriptor: str | None = None
    zones: list[Zone]


class ZoneSet(VDAStruct, kw_only=True):
    """``zoneSet`` message; the robot stores it DISABLED until ``enableZoneSet``."""

    header_id: HeaderId
    timestamp: str
    version: str
    manufacturer: str
    serial_number: str
    zone_set: ZoneSetDefinition
