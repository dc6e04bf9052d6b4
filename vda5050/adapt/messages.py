"""``visualization`` and ``connection`` between 3.0 and 2.x, and the pose they share with
``state`` (``mobileRobotPosition`` ↔ ``agvPosition``, ``localized`` ↔ ``positionInitialized``).

Connection: CONNECTION_BROKEN ↔ CONNECTIONBROKEN; HIBERNATING has no 2.x value and is kept as
the string ``"HIBERNATING"``. Visualization: ``plannedPath``, ``intermediatePath`` and
``referenceStateHeaderId`` exist only in 3.0.
"""

from __future__ import annotations

from vda5050 import v2, v3
from vda5050.adapt.common import to_v2, to_v3
from vda5050.enums import ConnectionState

__all__ = [
    "connection_v2_to_v3",
    "connection_v3_to_v2",
    "position_to_v2",
    "position_to_v3",
    "visualization_v2_to_v3",
    "visualization_v3_to_v2",
]


def visualization_v3_to_v2(message: v3.Visualization) -> v2.Visualization:
    """3.0 visualization as 2.x: pose and velocity (the paths are dropped)."""
    return v2.Visualization(
        header_id=message.header_id,
        timestamp=message.timestamp,
        version=message.version,
        manufacturer=message.manufacturer,
        serial_number=message.serial_number,
        agv_position=position_to_v2(message.mobile_robot_position),
        velocity=message.velocity,
    )


def visualization_v2_to_v3(
    message: v2.Visualization, *, reference_state_header_id: int | None = None
) -> v3.Visualization:
    """2.x visualization as 3.0; the header fields, optional in 2.x, are required.

    Raises:
        ValueError: if a header field is missing.
    """
    header = (message.header_id, message.timestamp, message.version)
    identity = (message.manufacturer, message.serial_number)
    if None in header or None in identity:
        raise ValueError("a 3.0 visualization needs all header fields")
    return v3.Visualization(
        header_id=message.header_id or 0,
        timestamp=message.timestamp or "",
        version=message.version or "",
        manufacturer=message.manufacturer or "",
        serial_number=message.serial_number or "",
        reference_state_header_id=reference_state_header_id,
        mobile_robot_position=position_to_v3(message.agv_position),
        velocity=message.velocity,
    )


def connection_v3_to_v2(message: v3.Connection) -> v2.Connection:
    """CONNECTION_BROKEN → CONNECTIONBROKEN; HIBERNATING stays the string "HIBERNATING"
    (connected but sending no states; master control's session reads it as online)."""
    return v2.Connection(
        header_id=message.header_id,
        timestamp=message.timestamp,
        version=message.version,
        manufacturer=message.manufacturer,
        serial_number=message.serial_number,
        connection_state=to_v2(ConnectionState, message.connection_state),
    )


def connection_v2_to_v3(message: v2.Connection) -> v3.Connection:
    """CONNECTIONBROKEN → CONNECTION_BROKEN (e.g. for the MQTT last will)."""
    return v3.Connection(
        header_id=message.header_id,
        timestamp=message.timestamp,
        version=message.version,
        manufacturer=message.manufacturer,
        serial_number=message.serial_number,
        connection_state=to_v3(v3.ConnectionState, message.connection_state),
    )


def position_to_v2(position: v3.MobileRobotPosition | None) -> v2.AgvPosition | None:
    """``mobileRobotPosition`` → ``agvPosition``."""
    if position is None:
        return None
    return v2.AgvPosition(
        x=position.x,
        y=position.y,
        theta=position.theta,
        map_id=position.map_id,
        position_initialized=position.localized,
        localization_score=position.localization_score,
        deviation_range=position.deviation_range,
    )


def position_to_v3(position: v2.AgvPosition | None) -> v3.MobileRobotPosition | None:
    """``agvPosition`` → ``mobileRobotPosition`` (``mapDescription`` is dropped)."""
    if position is None:
        return None
    return v3.MobileRobotPosition(
        x=position.x,
        y=position.y,
        theta=position.theta,
        map_id=position.map_id,
        localized=position.position_initialized,
        localization_score=position.localization_score,
        deviation_range=position.deviation_range,
    )
