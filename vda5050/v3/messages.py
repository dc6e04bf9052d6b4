"""Structs of the small 3.0.0 topics: ``visualization``, ``connection`` and ``responses``."""

from __future__ import annotations

from vda5050.v2.base import HeaderId, VDAStruct
from vda5050.v2.state import Velocity
from vda5050.v3.enums import ConnectionState, GrantType
from vda5050.v3.state import IntermediatePath, MobileRobotPosition, PlannedPath

__all__ = ["Connection", "Response", "Responses", "Visualization"]


class Visualization(VDAStruct, kw_only=True):
    """``visualization`` message (display only, REFERENCE §3 M.51).

    ``reference_state_header_id`` (the headerId of the state this pose belongs to) is
    required by the 3.0 schemas but optional here, so a robot that omits it is still shown;
    always set it when sending.
    """

    header_id: HeaderId
    timestamp: str
    version: str
    manufacturer: str
    serial_number: str
    reference_state_header_id: HeaderId | None = None
    planned_path: PlannedPath | None = None
    intermediate_path: IntermediatePath | None = None
    mobile_robot_position: MobileRobotPosition | None = None
    velocity: Velocity | None = None


class Connection(VDAStruct, kw_only=True):
    """``connection`` message (retained, QoS 1; CONNECTION_BROKEN is the MQTT last will)."""

    header_id: HeaderId
    timestamp: str
    version: str
    manufacturer: str
    serial_number: str
    connection_state: ConnectionState


class Response(VDAStruct, kw_only=True):
    """Fleet control's answer to a zone or edge request (REFERENCE §3 L.49).

    ``lease_expiry`` (ISO 8601) is only sent with GRANTED.
    """

    request_id: str
    grant_type: GrantType
    lease_expiry: str | None = None


class Responses(VDAStruct, kw_only=True):
    """``responses`` message (fleet control → robot)."""

    header_id: HeaderId
    timestamp: str
    version: str
    manufacturer: str
    serial_number: str
    responses: list[Response]
