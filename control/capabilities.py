"""What a vehicle accepts, from its factsheet: checks before an instant action is sent.

REFERENCE E.25 and J.45: besides the mandatory cancelOrder/startPause/stopPause, send only action
types, scopes and parameters the factsheet declares. I.39-41: nothing in MANUAL, SERVICE,
TEACHIN or STARTUP mode; in 3.0 INTERVENED only cancelOrder. A vehicle that has sent no
factsheet yet gets the safe default: the mandatory actions plus stateRequest and
factsheetRequest, which only read. E.23: an instant action must not conflict with the order
or the vehicle's state (`control.conflicts`). J.44: the factsheet's string limits are kept
with the other protocol limits (`control.limits` checks them before anything is sent).
"""

from collections.abc import Mapping
from dataclasses import dataclass

import vda5050
from vda5050.enums import ActionScope

MANDATORY_INSTANT = frozenset({"cancelOrder", "startPause", "stopPause"})
SAFE_DEFAULT_INSTANT = MANDATORY_INSTANT | {"stateRequest", "factsheetRequest"}
NO_ACTION_MODES = frozenset({"MANUAL", "SERVICE", "TEACHIN", "TEACH_IN", "STARTUP"})
# REFERENCE I.41: a 3.0 vehicle in INTERVENED keeps its order and takes orders and updates
# (run after it returns to AUTOMATIC/SEMIAUTOMATIC), but no instant action except cancelOrder.
ORDER_MODES = frozenset({"AUTOMATIC", "SEMIAUTOMATIC", "INTERVENED"})
INTERVENED_INSTANT = frozenset({"cancelOrder"})


@dataclass(frozen=True)
class StringLimits:
    """factsheet protocolLimits.maxStringLens (3.0 maximumStringLengths); None = no limit."""

    msg_len: int | None = None
    topic_serial_len: int | None = None
    topic_elem_len: int | None = None
    id_len: int | None = None
    id_numerical_only: bool = False
    enum_len: int | None = None
    load_id_len: int | None = None

    @property
    def limits_strings(self) -> bool:
        """Whether a limit applies to strings inside a message (ids, enums, loadId)."""
        return self.id_numerical_only or any(
            limit is not None for limit in (self.id_len, self.enum_len, self.load_id_len)
        )

    @classmethod
    def from_factsheet(cls, lens: vda5050.MaxStringLens) -> "StringLimits":
        # 0 means "no limit" like absent (REFERENCE J.44).
        return cls(
            msg_len=lens.msg_len or None,
            topic_serial_len=lens.topic_serial_len or None,
            topic_elem_len=lens.topic_elem_len or None,
            id_len=lens.id_len or None,
            id_numerical_only=bool(lens.id_numerical_only),
            enum_len=lens.enum_len or None,
            load_id_len=lens.load_id_len or None,
        )


@dataclass(frozen=True)
class Capabilities:
    """The actions a vehicle declared in its factsheet, by action type."""

    actions: Mapping[str, vda5050.AgvAction]
    optional_parameters: frozenset[str] = frozenset()  # SUPPORTED or REQUIRED (J.45)
    max_order_nodes: int | None = None  # maxArrayLens order.nodes / order.edges + 1
    min_order_interval: float = 0.0  # seconds between two orders or updates
    strings: StringLimits = StringLimits()

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
            strings=StringLimits.from_factsheet(limits.max_string_lens),
        )

    def declares_instant(self, action_type: str) -> bool:
        """Whether the factsheet lists `action_type` with the INSTANT scope."""
        spec = self.actions.get(action_type)
        return spec is not None and ActionScope.INSTANT in spec.action_scopes

    @property
    def retries_actions(self) -> bool:
        """3.0 E.27: order actions may be sent `retriable` only to a vehicle that takes the
        master's retry and skipRetry."""
        return self.declares_instant("retry") and self.declares_instant("skipRetry")


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
    if operating_mode == "INTERVENED" and action_type not in INTERVENED_INSTANT:
        return "vehicle is in INTERVENED mode, which takes no instant action but cancelOrder"
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
