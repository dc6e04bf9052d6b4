"""Structs of the small topics: ``visualization`` and ``connection``."""

from __future__ import annotations

from vda5050.enums import ConnectionState
from vda5050.v2.base import HeaderId, VDAStruct
from vda5050.v2.state import AgvPosition, Velocity


class Visualization(VDAStruct, kw_only=True):
    """``visualization`` message. Every field, header included, is optional in the schema."""

    header_id: HeaderId | None = None
    timestamp: str | None = None
    version: str | None = None
    manufacturer: str | None = None
    serial_number: str | None = None
    agv_position: AgvPosition | None = None
    velocity: Velocity | None = None


class Connection(VDAStruct, kw_only=True):
    """``connection`` message (retained, QoS 1; also the MQTT last will)."""

    header_id: HeaderId
    timestamp: str
    version: str
    manufacturer: str
    serial_number: str
    connection_state: ConnectionState
