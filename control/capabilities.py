"""What a vehicle accepts, from its factsheet: checks before an instant action is sent.

REFERENCE E.25 and J.45: besides the mandatory cancelOrder/startPause/stopPause, send only action
types, scopes and parameters the factsheet declares. I.39-41: nothing in MANUAL, SERVICE,
TEACHIN or STARTUP mode. A vehicle that has sent no factsheet yet gets the safe default: the
mandatory actions plus stateRequest and factsheetRequest, which only read.
"""

from collections.abc import Mapping
from dataclasses import dataclass

import vda5050
from vda5050.enums import ActionScope

MANDATORY_INSTANT = frozenset({"cancelOrder", "startPause", "stopPause"})
SAFE_DEFAULT_INSTANT = MANDATORY_INSTANT | {"stateRequest", "factsheetRequest"}
NO_ACTION_MODES = frozenset({"MANUAL", "SERVICE", "TEACHIN", "TEACH_IN", "STARTUP"})


@dataclass(frozen=True)
class Capabilities:
    """The actions a vehicle declared in its factsheet, by action type."""

    actions: Mapping[str, vda5050.AgvAction]
    optional_parameters: frozenset[str] = frozenset()  # SUPPORTED or REQUIRED (J.45)
    max_order_nodes: int | None = None  # maxArrayLens order.nodes / order.edges + 1
    min_order_interval: float = 0.0  # seconds between two orders or updates

    @classmethod
    def from_factsheet(cls, factsheet: vda5050.Factsheet) -> "Capabilities":
        limits = factsheet.protocol_limits
        arrays = [
            n
            for n in (
                limits.max_array_lens.order_nodes,
                _plus_one(limits.max_array_lens.order_edges),
            )
            if n
        ]
        return cls(
            {a.action_type: a for a in factsheet.protocol_features.agv_actions},
            optional_parameters=frozenset(
                p.parameter for p in factsheet.protocol_features.optional_parameters
            ),
            max_order_nodes=min(arrays) if arrays else None,  # 0/absent = no limit (J.44)
            min_order_interval=limits.timing.min_order_interval or 0.0,
        )


def sends_max_speed(capabilities: Capabilities | None) -> bool:
    """Whether edges may carry `maxSpeed` (A.6: only optional fields the vehicle supports)."""
    if capabilities is None:
        return False
    names = {"order.edges.maxSpeed", "order.edges.maximumSpeed", "order.edge.maxSpeed"}
    return not names.isdisjoint(capabilities.optional_parameters)


def _plus_one(value: int | None) -> int | None:
    return value + 1 if value else None


def refuse_instant_action(
    capabilities: Capabilities | None,
    operating_mode: str | None,
    action_type: str,
    parameters: Mapping[str, object],
) -> str | None:
    """Why `action_type` with `parameters` must not be sent now, or None if it may."""
    if operating_mode in NO_ACTION_MODES:
        return f"vehicle is in {operating_mode} mode, which takes no actions"
    if capabilities is None:
        if action_type in SAFE_DEFAULT_INSTANT:
            return None
        return f"{action_type} needs a factsheet that declares it; none received yet"
    spec = capabilities.actions.get(action_type)
    if spec is None or ActionScope.INSTANT not in spec.action_scopes:
        if action_type in MANDATORY_INSTANT:
            return None  # every vehicle must support these, declared or not
        return f"the factsheet declares no instant action {action_type}"
    declared = {p.key: p for p in spec.action_parameters or []}
    missing = sorted(k for k, p in declared.items() if not p.is_optional and k not in parameters)
    if missing:
        return f"{action_type} needs parameters {', '.join(missing)}"
    unknown = sorted(set(parameters) - declared.keys())
    if unknown:
        return f"{action_type} does not take parameters {', '.join(unknown)}"
    return None
