"""Action catalogue of the simulated vehicle and the runtime record of one action.

The catalogue is the single source of truth for both the factsheet
(``protocolFeatures.agvActions`` / 3.0 ``mobileRobotActions``) and order validation, so the
vehicle never accepts an action it does not advertise and never advertises one it cannot
execute. Some entries exist only in 3.0 (``majors``); their blockingTypes may include SINGLE.
Action types are the 2.x names (``initPosition``); the 3.0 message edge renames them.
"""

from __future__ import annotations

from dataclasses import dataclass

from vda5050 import Action, action_params, v3
from vda5050.adapt import RETRIABLE_MARKER, retriable_result
from vda5050.enums import ActionScope, ActionStatus, BlockingType, ValueDataType

I = ActionScope.INSTANT  # noqa: E741 - short aliases keep the catalogue table readable
N = ActionScope.NODE
ALL_BLOCKING = (BlockingType.NONE, BlockingType.SOFT, BlockingType.HARD)
STANDING = (BlockingType.SOFT, BlockingType.HARD)
HARD = (BlockingType.HARD,)
#: 3.0: SINGLE = driving allowed, no other action in parallel.
WITH_SINGLE = (BlockingType.NONE, v3.BlockingType.SINGLE, BlockingType.SOFT, BlockingType.HARD)
ONLY_V3 = frozenset({3})

TERMINAL = frozenset({ActionStatus.FINISHED, ActionStatus.FAILED})


@dataclass(frozen=True, slots=True)
class ParamSpec:
    """One declared action parameter."""

    key: str
    data_type: ValueDataType
    optional: bool
    description: str


@dataclass(frozen=True, slots=True)
class ActionSpec:
    """What the simulator supports for one action type."""

    action_type: str
    scopes: tuple[ActionScope, ...]
    blocking_types: tuple[str, ...]
    """BlockingType members (and 3.0's SINGLE) allowed for node actions."""
    description: str
    duration: float = 0.0
    """Simulated seconds the action spends RUNNING when executed as a node action."""
    parameters: tuple[ParamSpec, ...] = ()
    majors: frozenset[int] = frozenset({2, 3})
    """Protocol major versions in which the vehicle offers this action."""

    @property
    def required_keys(self) -> frozenset[str]:
        """Parameter keys the master control must send."""
        return frozenset(p.key for p in self.parameters if not p.optional)


def _str(key: str, description: str, optional: bool = True) -> ParamSpec:
    return ParamSpec(key, ValueDataType.STRING, optional, description)


def _num(key: str, description: str, optional: bool = False) -> ParamSpec:
    return ParamSpec(key, ValueDataType.NUMBER, optional, description)


_LOAD_PARAMS = (
    _str("loadId", "Id of the load; copied into state.loads."),
    _str("loadType", "Type of the load; copied into state.loads."),
    _str("stationType", "Informational only."),
    _str("stationName", "Informational only."),
    _str("lhd", "Load handling device; copied into loads[].loadPosition."),
)
_INIT_PARAMS = (
    _num("x", "x in metres."),
    _num("y", "y in metres."),
    _num("theta", "Heading in radians."),
    _str("mapId", "Map of the new position; must be the simulator's map.", optional=False),
    _str("lastNodeId", "Node the vehicle now stands on.", optional=False),
)

CATALOGUE: dict[str, ActionSpec] = {
    spec.action_type: spec
    for spec in (
        ActionSpec("pick", (N,), STANDING, "Pick up a load (sets state.loads).", 2.0, _LOAD_PARAMS),
        ActionSpec("drop", (N,), STANDING, "Drop the load (state.loads = []).", 2.0, _LOAD_PARAMS),
        ActionSpec("startCharging", (I, N), STANDING, "Connect the charger.", 1.0),
        ActionSpec("stopCharging", (I, N), STANDING, "Disconnect the charger.", 1.0),
        ActionSpec("cancelOrder", (I,), ALL_BLOCKING, "Stop at the next node, drop the order."),
        ActionSpec("startPause", (I,), ALL_BLOCKING, "Pause driving and actions."),
        ActionSpec("stopPause", (I,), ALL_BLOCKING, "Resume after startPause."),
        ActionSpec("stateRequest", (I,), ALL_BLOCKING, "Publish a state message now."),
        ActionSpec("factsheetRequest", (I,), ALL_BLOCKING, "Publish the factsheet now."),
        ActionSpec("initPosition", (I, N), HARD, "Set pose and lastNodeId.", 0.5, _INIT_PARAMS),
        ActionSpec(
            "logReport",
            (I,),
            ALL_BLOCKING,
            "Write a log report (logged by the simulator; finishes at once).",
            parameters=(_str("reason", "Why the report is requested.", optional=False),),
        ),
        ActionSpec(
            "detectObject",
            (N,),
            WITH_SINGLE,
            "Look for an object (simulated: always succeeds); SINGLE keeps driving.",
            1.0,
            (_str("objectType", "Informational only."),),
            majors=ONLY_V3,
        ),
        ActionSpec(
            "retry",
            (I,),
            ALL_BLOCKING,
            "Run a RETRIABLE order action again (REFERENCE E.27).",
            parameters=(_str("actionId", "The RETRIABLE action.", optional=False),),
            majors=ONLY_V3,
        ),
        ActionSpec(
            "skipRetry",
            (I,),
            ALL_BLOCKING,
            "Give up a RETRIABLE order action: it ends FAILED, the order goes on.",
            parameters=(_str("actionId", "The RETRIABLE action.", optional=False),),
            majors=ONLY_V3,
        ),
        ActionSpec(
            "downloadMap",
            (I,),
            ALL_BLOCKING,
            "Download a map version over HTTP (2.1+); stored DISABLED.",
            parameters=(
                _str("mapId", "Map to download.", optional=False),
                _str("mapVersion", "Version to download.", optional=False),
                _str("mapDownloadLink", "http(s) URL of the file.", optional=False),
                _str("mapHash", "SHA-256 hex digest of the file."),
            ),
        ),
        ActionSpec(
            "enableMap",
            (I,),
            ALL_BLOCKING,
            "Enable a stored map version (2.1+), disabling the map's others.",
            parameters=(
                _str("mapId", "Map to enable.", optional=False),
                _str("mapVersion", "Version to enable.", optional=False),
            ),
        ),
        ActionSpec(
            "deleteMap",
            (I,),
            ALL_BLOCKING,
            "Delete a stored, disabled map version (2.1+).",
            parameters=(
                _str("mapId", "Map to delete.", optional=False),
                _str("mapVersion", "Version to delete.", optional=False),
            ),
        ),
        ActionSpec(
            "enableZoneSet",
            (I,),
            ALL_BLOCKING,
            "Enable a zone set received on the zoneSet topic (one per map).",
            parameters=(_str("zoneSetId", "Zone set to enable.", optional=False),),
            majors=ONLY_V3,
        ),
        ActionSpec(
            "clearInstantActions",
            (I,),
            ALL_BLOCKING,
            "Remove finished and failed instant actions from instantActionStates.",
            majors=ONLY_V3,
        ),
    )
}


def catalogue(major: int) -> list[ActionSpec]:
    """The actions offered in protocol major version ``major``, in catalogue order."""
    return [spec for spec in CATALOGUE.values() if major in spec.majors]


def check_action(action: Action, scope: ActionScope, major: int = 2) -> str | None:
    """Return why ``action`` cannot be used in ``scope`` (of protocol ``major``), or ``None``
    if it is acceptable."""
    spec = CATALOGUE.get(action.action_type)
    if spec is None or major not in spec.majors:
        return f"unsupported actionType {action.action_type!r}"
    if scope not in spec.scopes:
        return f"actionType {action.action_type!r} not supported in scope {scope}"
    if scope is not ActionScope.INSTANT and action.blocking_type not in spec.blocking_types:
        return f"blockingType {action.blocking_type} not supported for {action.action_type!r}"
    missing = spec.required_keys - action_params(action).keys()
    if missing:
        return f"{action.action_type!r} lacks parameters {sorted(missing)}"
    return None


@dataclass(slots=True)
class ActionRun:
    """Runtime record of one order or instant action, reported in ``actionStates``."""

    action: Action
    node_key: tuple[str, int] | None = None
    """(nodeId, sequenceId) of the node that triggers this order action; None for instant."""
    status: ActionStatus = ActionStatus.WAITING
    remaining: float = 0.0
    result: str | None = None

    @property
    def action_id(self) -> str:
        """The action's id."""
        return self.action.action_id

    @property
    def terminal(self) -> bool:
        """True once FINISHED or FAILED."""
        return self.status in TERMINAL

    @property
    def active(self) -> bool:
        """True while INITIALIZING or RUNNING."""
        return self.status in (ActionStatus.INITIALIZING, ActionStatus.RUNNING)

    @property
    def retriable(self) -> bool:
        """3.0: failed but waiting for retry/skipRetry (RETRIABLE, carried as marked PAUSED)."""
        return self.status is ActionStatus.PAUSED and (self.result or "").startswith(
            RETRIABLE_MARKER
        )

    def hold_for_retry(self, reason: str) -> None:
        """3.0 E.27: a `retriable` order action that failed waits for the master."""
        self.status = ActionStatus.PAUSED
        self.result = retriable_result(reason)

    def fail(self, reason: str) -> None:
        """Mark the action FAILED with a human-readable reason."""
        self.status = ActionStatus.FAILED
        self.result = reason
