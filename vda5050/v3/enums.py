"""String enumerations of VDA 5050 3.0.0 (REFERENCE §5).

3.0 spells values UPPER_SNAKE_CASE (``CONNECTION_BROKEN``, ``TEACH_IN``) and extends several
2.x enums, so the enums that changed are redefined here under their 2.x names; those with
identical values are re-exported from :mod:`vda5050.enums`. "Extensible" enums of the
factsheet (kinematics, class, localization/navigation types, wheel type) list the predefined
values for producers; the Struct fields stay ``str`` so that vendor values decode.
"""

from __future__ import annotations

from enum import StrEnum

from vda5050.enums import InfoLevel, LocalizationType, MapStatus, OrientationType, Support

__all__ = [
    "ActionScope",
    "ActionStatus",
    "ActionType",
    "ActiveEmergencyStop",
    "BidirectedLimitation",
    "BlockingType",
    "ConnectionState",
    "CorridorReferencePoint",
    "CorridorReleaseLossBehavior",
    "DirectedLimitation",
    "EdgeRequestType",
    "ErrorLevel",
    "ErrorType",
    "GrantType",
    "InfoLevel",
    "LocalizationType",
    "MapStatus",
    "MobileRobotClass",
    "MobileRobotKinematics",
    "NavigationType",
    "OperatingMode",
    "OrientationType",
    "RequestStatus",
    "Support",
    "ValueDataType",
    "WheelType",
    "ZoneReleaseLossBehavior",
    "ZoneRequestType",
    "ZoneSetStatus",
    "ZoneType",
]


class ConnectionState(StrEnum):
    """``connection.connectionState``; HIBERNATING = connected but sending no states."""

    ONLINE = "ONLINE"
    OFFLINE = "OFFLINE"
    HIBERNATING = "HIBERNATING"
    CONNECTION_BROKEN = "CONNECTION_BROKEN"


class OperatingMode(StrEnum):
    """``state.operatingMode`` (3.0 §6.6.6): STARTUP and INTERVENED are new."""

    STARTUP = "STARTUP"
    AUTOMATIC = "AUTOMATIC"
    SEMIAUTOMATIC = "SEMIAUTOMATIC"
    INTERVENED = "INTERVENED"
    MANUAL = "MANUAL"
    SERVICE = "SERVICE"
    TEACH_IN = "TEACH_IN"


class ActionStatus(StrEnum):
    """``actionStatus``; RETRIABLE = failed, waiting for ``retry``/``skipRetry``."""

    WAITING = "WAITING"
    INITIALIZING = "INITIALIZING"
    RUNNING = "RUNNING"
    PAUSED = "PAUSED"
    RETRIABLE = "RETRIABLE"
    FINISHED = "FINISHED"
    FAILED = "FAILED"


class BlockingType(StrEnum):
    """``action.blockingType``; SINGLE = driving allowed, no other action in parallel.

    Instant actions are always NONE in 3.0 (REFERENCE §3 E.23).
    """

    NONE = "NONE"
    SINGLE = "SINGLE"
    SOFT = "SOFT"
    HARD = "HARD"


class ErrorLevel(StrEnum):
    """``errors[].errorLevel`` (REFERENCE §3 G.36).

    WARNING/URGENT: the robot continues; CRITICAL: it cannot continue the order but can take
    a new one; FATAL: it can do neither without a human.
    """

    WARNING = "WARNING"
    URGENT = "URGENT"
    CRITICAL = "CRITICAL"
    FATAL = "FATAL"


class ActiveEmergencyStop(StrEnum):
    """``safetyState.activeEmergencyStop`` (2.x ``eStop`` without AUTOACK)."""

    MANUAL = "MANUAL"
    REMOTE = "REMOTE"
    NONE = "NONE"


class ZoneSetStatus(StrEnum):
    """``state.zoneSets[].zoneSetStatus``."""

    ENABLED = "ENABLED"
    DISABLED = "DISABLED"


class CorridorReferencePoint(StrEnum):
    """``edge.corridor.corridorReferencePoint`` (2.1 ``corridorRefPoint``)."""

    KINEMATIC_CENTER = "KINEMATIC_CENTER"
    CONTOUR = "CONTOUR"


class CorridorReleaseLossBehavior(StrEnum):
    """``edge.corridor.releaseLossBehavior`` (default STOP)."""

    STOP = "STOP"
    RETURN = "RETURN"


class ZoneType(StrEnum):
    """``zoneSet.zones[].zoneType`` (3.0 §6.4)."""

    BLOCKED = "BLOCKED"
    LINE_GUIDED = "LINE_GUIDED"
    RELEASE = "RELEASE"
    COORDINATED_REPLANNING = "COORDINATED_REPLANNING"
    SPEED_LIMIT = "SPEED_LIMIT"
    ACTION = "ACTION"
    PRIORITY = "PRIORITY"
    PENALTY = "PENALTY"
    DIRECTED = "DIRECTED"
    BIDIRECTED = "BIDIRECTED"


class ZoneReleaseLossBehavior(StrEnum):
    """``releaseLossBehavior`` of a RELEASE zone."""

    STOP = "STOP"
    CONTINUE = "CONTINUE"
    EVACUATE = "EVACUATE"


class DirectedLimitation(StrEnum):
    """``directedLimitation`` of a DIRECTED zone."""

    SOFT = "SOFT"
    RESTRICTED = "RESTRICTED"
    STRICT = "STRICT"


class BidirectedLimitation(StrEnum):
    """``bidirectedLimitation`` of a BIDIRECTED zone."""

    SOFT = "SOFT"
    RESTRICTED = "RESTRICTED"


class ZoneRequestType(StrEnum):
    """``state.zoneRequests[].requestType``."""

    ACCESS = "ACCESS"
    REPLANNING = "REPLANNING"


class EdgeRequestType(StrEnum):
    """``state.edgeRequests[].requestType``."""

    CORRIDOR = "CORRIDOR"


class RequestStatus(StrEnum):
    """``requestStatus`` of zone and edge requests.

    QUEUED is named by the document (3.0 §6.9) but missing from the schema; it is accepted
    because the document wins on conflict (REFERENCE header).
    """

    REQUESTED = "REQUESTED"
    QUEUED = "QUEUED"
    GRANTED = "GRANTED"
    REVOKED = "REVOKED"
    EXPIRED = "EXPIRED"


class GrantType(StrEnum):
    """``responses[].grantType`` (fleet control's answer to a request)."""

    GRANTED = "GRANTED"
    QUEUED = "QUEUED"
    REVOKED = "REVOKED"
    REJECTED = "REJECTED"


class ActionScope(StrEnum):
    """``mobileRobotActions[].actionScopes[]``; ZONE is new."""

    INSTANT = "INSTANT"
    NODE = "NODE"
    EDGE = "EDGE"
    ZONE = "ZONE"


class ValueDataType(StrEnum):
    """``actionParameters[].valueDataType`` (FLOAT was removed in 3.0)."""

    BOOL = "BOOL"
    NUMBER = "NUMBER"
    INTEGER = "INTEGER"
    STRING = "STRING"
    OBJECT = "OBJECT"
    ARRAY = "ARRAY"


class MobileRobotKinematics(StrEnum):
    """Predefined ``typeSpecification.mobileRobotKinematics`` values (extensible)."""

    DIFFERENTIAL = "DIFFERENTIAL"
    OMNIDIRECTIONAL = "OMNIDIRECTIONAL"
    THREE_WHEEL = "THREE_WHEEL"


class MobileRobotClass(StrEnum):
    """Predefined ``typeSpecification.mobileRobotClass`` values (extensible)."""

    FORKLIFT = "FORKLIFT"
    CONVEYOR = "CONVEYOR"
    TUGGER = "TUGGER"
    CARRIER = "CARRIER"


class NavigationType(StrEnum):
    """Predefined ``navigationTypes`` values (extensible; 2.x AUTONOMOUS is FREELY_NAVIGATING)."""

    PHYSICAL_LINE_GUIDED = "PHYSICAL_LINE_GUIDED"
    VIRTUAL_LINE_GUIDED = "VIRTUAL_LINE_GUIDED"
    FREELY_NAVIGATING = "FREELY_NAVIGATING"


class WheelType(StrEnum):
    """Predefined ``wheelDefinitions[].type`` values (extensible)."""

    DRIVE = "DRIVE"
    CASTER = "CASTER"
    FIXED = "FIXED"
    MECANUM = "MECANUM"


class ActionType(StrEnum):
    """Predefined 3.0 action types (REFERENCE §4); vendors may define more."""

    START_PAUSE = "startPause"
    STOP_PAUSE = "stopPause"
    START_CHARGING = "startCharging"
    STOP_CHARGING = "stopCharging"
    INITIALIZE_POSITION = "initializePosition"
    ENABLE_MAP = "enableMap"
    DOWNLOAD_MAP = "downloadMap"
    DELETE_MAP = "deleteMap"
    STATE_REQUEST = "stateRequest"
    LOG_REPORT = "logReport"
    PICK = "pick"
    DROP = "drop"
    DETECT_OBJECT = "detectObject"
    FINE_POSITIONING = "finePositioning"
    WAIT_FOR_TRIGGER = "waitForTrigger"
    TRIGGER = "trigger"
    CANCEL_ORDER = "cancelOrder"
    FACTSHEET_REQUEST = "factsheetRequest"
    START_HIBERNATION = "startHibernation"
    STOP_HIBERNATION = "stopHibernation"
    SHUTDOWN = "shutdown"
    DOWNLOAD_ZONE_SET = "downloadZoneSet"
    ENABLE_ZONE_SET = "enableZoneSet"
    DELETE_ZONE_SET = "deleteZoneSet"
    CLEAR_INSTANT_ACTIONS = "clearInstantActions"
    CLEAR_ZONE_ACTIONS = "clearZoneActions"
    RETRY = "retry"
    SKIP_RETRY = "skipRetry"
    UPDATE_CERTIFICATE = "updateCertificate"


class ErrorType(StrEnum):
    """Predefined 3.0 error types (REFERENCE §3 C.18, §5); ``Error.error_type`` stays ``str``.

    INVALID_ORDER_ACTION is spelt that way in the text; one enum listing says INVALID_ORDER.
    """

    VALIDATION_FAILURE = "VALIDATION_FAILURE"
    UNSUPPORTED_PARAMETER = "UNSUPPORTED_PARAMETER"
    INVALID_ORDER_ACTION = "INVALID_ORDER_ACTION"
    INVALID_INSTANT_ACTION = "INVALID_INSTANT_ACTION"
    OUTDATED_ORDER_UPDATE = "OUTDATED_ORDER_UPDATE"
    SAME_ORDER_UPDATE_ID = "SAME_ORDER_UPDATE_ID"
    ORDER_UPDATE_FOLLOWING_CANCEL = "ORDER_UPDATE_FOLLOWING_CANCEL"
    OTHER_ORDER_ACTIVE = "OTHER_ORDER_ACTIVE"
    START_NODE_OUT_OF_RANGE = "START_NODE_OUT_OF_RANGE"
    NO_ROUTE_TO_TARGET = "NO_ROUTE_TO_TARGET"
    MOBILE_ROBOT_NOT_AVAILABLE = "MOBILE_ROBOT_NOT_AVAILABLE"
    UNKNOWN_MAP_ID = "UNKNOWN_MAP_ID"
    INSUFFICIENT_MEMORY = "INSUFFICIENT_MEMORY"
    NO_ORDER_TO_CANCEL = "NO_ORDER_TO_CANCEL"
    DUPLICATE_MAP = "DUPLICATE_MAP"
    DUPLICATE_ZONE_SET = "DUPLICATE_ZONE_SET"
    BLOCKED_ZONE_VIOLATION = "BLOCKED_ZONE_VIOLATION"
    RELEASE_LOST = "RELEASE_LOST"
    ZONE_ACTION_CONFLICT = "ZONE_ACTION_CONFLICT"
    NODE_UNREACHABLE = "NODE_UNREACHABLE"
    OUTSIDE_OF_CORRIDOR = "OUTSIDE_OF_CORRIDOR"
    LOCALIZATION_ERROR = "LOCALIZATION_ERROR"
    INSTANT_ACTION_STATES_FULL = "INSTANT_ACTION_STATES_FULL"
    ZONE_ACTION_STATES_FULL = "ZONE_ACTION_STATES_FULL"
