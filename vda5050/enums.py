"""String enumerations of VDA 5050 2.x (REFERENCE §5).

All enums are :class:`enum.StrEnum`, so members compare equal to (and serialise as) their
wire spelling. 2.x spells values UPPERCASE without underscores (``CONNECTIONBROKEN``,
``TEACHIN``); 3.0 spellings are deliberately absent because 3.0 is not wire-compatible (they
live in :mod:`vda5050.v3.enums`). Only :class:`TopicKind` is shared by all versions.
"""

from __future__ import annotations

from enum import StrEnum


class TopicKind(StrEnum):
    """Last level of a VDA 5050 MQTT topic, i.e. the message type.

    ZONE_SET and RESPONSES exist only in 3.0; :func:`vda5050.topics.kinds_of` tells which
    kinds a protocol major version has (2.x: the first six, 1.1: no factsheet either).
    """

    ORDER = "order"
    INSTANT_ACTIONS = "instantActions"
    STATE = "state"
    VISUALIZATION = "visualization"
    CONNECTION = "connection"
    FACTSHEET = "factsheet"
    ZONE_SET = "zoneSet"
    RESPONSES = "responses"


class ProtocolVersion(StrEnum):
    """Protocol versions this package speaks (value of the header ``version`` field)."""

    V2_0_0 = "2.0.0"
    V2_1_0 = "2.1.0"


class ConnectionState(StrEnum):
    """``connection.connectionState``."""

    ONLINE = "ONLINE"
    OFFLINE = "OFFLINE"
    CONNECTIONBROKEN = "CONNECTIONBROKEN"


class OperatingMode(StrEnum):
    """``state.operatingMode``."""

    AUTOMATIC = "AUTOMATIC"
    SEMIAUTOMATIC = "SEMIAUTOMATIC"
    MANUAL = "MANUAL"
    SERVICE = "SERVICE"
    TEACHIN = "TEACHIN"


class ActionStatus(StrEnum):
    """``state.actionStates[].actionStatus``.

    PAUSED is in the 2.0 schema and the 2.1 document but missing from the 2.1 schema
    (upstream bug, REFERENCE §5); we accept it for both versions.
    """

    WAITING = "WAITING"
    INITIALIZING = "INITIALIZING"
    RUNNING = "RUNNING"
    PAUSED = "PAUSED"
    FINISHED = "FINISHED"
    FAILED = "FAILED"


class BlockingType(StrEnum):
    """``action.blockingType``: whether an action may run while driving / in parallel."""

    NONE = "NONE"
    SOFT = "SOFT"
    HARD = "HARD"


class ErrorLevel(StrEnum):
    """``state.errors[].errorLevel``."""

    WARNING = "WARNING"
    FATAL = "FATAL"


class InfoLevel(StrEnum):
    """``state.information[].infoLevel``."""

    DEBUG = "DEBUG"
    INFO = "INFO"


class EStop(StrEnum):
    """``state.safetyState.eStop``."""

    AUTOACK = "AUTOACK"
    MANUAL = "MANUAL"
    REMOTE = "REMOTE"
    NONE = "NONE"


class OrientationType(StrEnum):
    """``order.edges[].orientationType`` (absent means TANGENTIAL)."""

    GLOBAL = "GLOBAL"
    TANGENTIAL = "TANGENTIAL"


class MapStatus(StrEnum):
    """``state.maps[].mapStatus`` (2.1)."""

    ENABLED = "ENABLED"
    DISABLED = "DISABLED"


class CorridorRefPoint(StrEnum):
    """``order.edges[].corridor.corridorRefPoint`` (2.1)."""

    KINEMATICCENTER = "KINEMATICCENTER"
    CONTOUR = "CONTOUR"


class AgvKinematic(StrEnum):
    """``factsheet.typeSpecification.agvKinematic``."""

    DIFF = "DIFF"
    OMNI = "OMNI"
    THREEWHEEL = "THREEWHEEL"


class AgvClass(StrEnum):
    """``factsheet.typeSpecification.agvClass``."""

    FORKLIFT = "FORKLIFT"
    CONVEYOR = "CONVEYOR"
    TUGGER = "TUGGER"
    CARRIER = "CARRIER"


class LocalizationType(StrEnum):
    """Values of ``factsheet.typeSpecification.localizationTypes`` (enum since 2.1).

    The Struct field is typed ``list[str]`` because 2.0 allows free text; use these
    members when producing factsheets.
    """

    NATURAL = "NATURAL"
    REFLECTOR = "REFLECTOR"
    RFID = "RFID"
    DMC = "DMC"
    SPOT = "SPOT"
    GRID = "GRID"


class NavigationType(StrEnum):
    """Values of ``factsheet.typeSpecification.navigationTypes`` (enum since 2.1).

    Typed ``list[str]`` in the Struct for the same reason as :class:`LocalizationType`.
    """

    PHYSICAL_LINE_GUIDED = "PHYSICAL_LINE_GUIDED"
    VIRTUAL_LINE_GUIDED = "VIRTUAL_LINE_GUIDED"
    AUTONOMOUS = "AUTONOMOUS"


class Support(StrEnum):
    """``factsheet.protocolFeatures.optionalParameters[].support``."""

    SUPPORTED = "SUPPORTED"
    REQUIRED = "REQUIRED"


class ActionScope(StrEnum):
    """``factsheet.protocolFeatures.agvActions[].actionScopes[]``."""

    INSTANT = "INSTANT"
    NODE = "NODE"
    EDGE = "EDGE"


class ValueDataType(StrEnum):
    """``factsheet.protocolFeatures.agvActions[].actionParameters[].valueDataType``."""

    BOOL = "BOOL"
    NUMBER = "NUMBER"
    INTEGER = "INTEGER"
    FLOAT = "FLOAT"
    STRING = "STRING"
    OBJECT = "OBJECT"
    ARRAY = "ARRAY"


class WheelType(StrEnum):
    """``factsheet.agvGeometry.wheelDefinitions[].type``."""

    DRIVE = "DRIVE"
    CASTER = "CASTER"
    FIXED = "FIXED"
    MECANUM = "MECANUM"


class ActionType(StrEnum):
    """Predefined 2.x action types (REFERENCE §4).

    ``Action.action_type`` stays a plain ``str`` because vendors may define their own.
    """

    START_PAUSE = "startPause"
    STOP_PAUSE = "stopPause"
    START_CHARGING = "startCharging"
    STOP_CHARGING = "stopCharging"
    INIT_POSITION = "initPosition"
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
    CANCEL_ORDER = "cancelOrder"
    FACTSHEET_REQUEST = "factsheetRequest"


class ErrorType(StrEnum):
    """Error types named by the 2.x specification (REFERENCE §3 C/D).

    ``Error.error_type`` stays a plain ``str``: every other error type is vendor-specific.
    """

    VALIDATION_ERROR = "validationError"
    ORDER_ERROR = "orderError"
    ORDER_UPDATE_ERROR = "orderUpdateError"
    NO_ORDER_TO_CANCEL = "noOrderToCancel"
