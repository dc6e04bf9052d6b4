"""Execution of one transport order as one VDA 5050 order, tracked from the vehicle's state.

Pure logic without MQTT or the database: `build_order` turns a route into an order message and
`OrderExecution.observe` turns each state into progress events for the flusher to persist.
"""

import enum
import time
import uuid
from collections import Counter
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

import vda5050
from control.rejections import rejection_reason

TERMINAL = {"FINISHED", "FAILED"}


@dataclass(frozen=True)
class NodePlace:
    """Where a layout node is (metres, radians) and on which VDA 5050 map."""

    x: float
    y: float
    theta: float | None
    map_id: str


@dataclass(frozen=True)
class LayoutIndex:
    """A map's nodes and directed edges, as `control` needs them to build orders."""

    map_id: str
    nodes: dict[str, NodePlace]
    edges: dict[tuple[str, str], str]  # (start node, end node) -> edge id
    speed_limits: dict[str, float] = field(default_factory=dict)  # edge id -> m/s, after zones
    parking: dict[str, str] = field(default_factory=dict)  # PARK station id -> its node id
    # Node id -> [x, y] in centimetres as the live page gets it (filled on first use).
    points: dict[str, list[float]] = field(default_factory=dict, compare=False, repr=False)


class Phase(enum.StrEnum):
    SENT = "SENT"
    RUNNING = "RUNNING"
    CANCELLING = "CANCELLING"
    DONE = "DONE"


@dataclass(frozen=True)
class Window:
    """Route indices `first`..`last` go out; `first`..`released` are base, the rest horizon."""

    first: int
    last: int
    released: int


@dataclass(frozen=True)
class Progress:
    """Something that happened to a transport order, to be persisted by the flusher."""

    kind: str  # sent | started | step | finished | failed | cancelled | requeued
    order_id: int
    detail: dict[str, str] = field(default_factory=dict)


@dataclass(frozen=True)
class StepPlan:
    """A stop of a transport order as dispatch planned it: at route index `index`, do
    `action_type` (pick, drop or a custom action) for `station` with `parameters`."""

    index: int
    action_type: str
    station: str = ""
    parameters: dict[str, Any] = field(default_factory=dict)


@dataclass
class StepAction:
    """A stop being driven: its node action's id and its current route index (traffic may
    re-plan the route between stops; see `OrderExecution.move_stops`)."""

    index: int
    action_type: str
    action_id: str
    station: str = ""
    parameters: dict[str, Any] = field(default_factory=dict)


@dataclass
class OrderExecution:
    """One transport order being driven by one vehicle as VDA 5050 order `vda_order_id`.

    `steps` are its stops in order, each a node action; the last is at the route's end."""

    transport_order_id: int
    vda_order_id: str
    route: list[str]
    steps: list[StepAction] = field(default_factory=list)
    first_stop: int = 0  # route index of the only stop of an order without steps (charge)
    phase: Phase = Phase.SENT
    sent_monotonic: float = field(default_factory=time.monotonic)
    cancel_action_id: str | None = None
    steps_done: set[str] = field(default_factory=set)
    released_until: int = -1  # route index of the last base node sent
    update_id: int = -1  # orderUpdateId of the latest message sent
    confirmed_update: int = -1  # latest orderUpdateId the vehicle's state showed
    attempts: int = 0  # sends of the latest message (resends are identical)
    window: Window | None = None  # what the latest message carried
    kind: str = "transport"  # or "charge", "park" (control.ports.ActiveOrder.kind)
    retries: dict[str, int] = field(default_factory=dict)  # 3.0 retry sent, by action id
    # The actionStates `observe` last went through and whether all our actions had ended then:
    # states repeat them unchanged most of the time, and then there is nothing new in them.
    _seen_actions: list[Any] | None = field(default=None, init=False, repr=False, compare=False)
    _actions_ended: bool = field(default=False, init=False, repr=False, compare=False)

    @property
    def awaiting_confirmation(self) -> bool:
        return self.update_id > self.confirmed_update

    @property
    def fully_released(self) -> bool:
        return self.released_until >= len(self.route) - 1

    def sent(self, update_id: int, window: Window) -> None:
        """Record that a message (new, update or identical resend) went out."""
        self.attempts = self.attempts + 1 if update_id == self.update_id else 1
        self.update_id, self.window, self.released_until = update_id, window, window.released
        self.sent_monotonic = time.monotonic()

    @classmethod
    def plan(
        cls,
        *,
        transport_order_id: int,
        vda_order_id: str,
        route: list[str],
        pickup: str | None = None,
        kind: str = "transport",
        steps: Sequence[StepPlan] = (),
    ) -> "OrderExecution":
        """Without `steps`, a transport order picks at `pickup` and drops at the route's end."""
        first = route.index(pickup) if pickup in route else 0
        if not steps and kind == "transport":
            steps = (StepPlan(first, "pick"), StepPlan(len(route) - 1, "drop"))
        counts = Counter(step.action_type for step in steps)
        return cls(
            transport_order_id=transport_order_id,
            vda_order_id=vda_order_id,
            route=route,
            # Derived from the order id, so a restarted control recognises them; an action type
            # that occurs once keeps the short form (`TO-7-pick`) that pick → drop orders had.
            steps=[
                StepAction(
                    step.index,
                    step.action_type,
                    f"{vda_order_id}-{step.action_type}"
                    if counts[step.action_type] == 1
                    else f"{vda_order_id}-{number}-{step.action_type}",
                    step.station,
                    dict(step.parameters),
                )
                for number, step in enumerate(steps, start=1)
            ],
            first_stop=first,
            kind=kind,
        )

    @property
    def action_steps(self) -> dict[str, str]:
        if self.kind == "charge":  # a charge session: one startCharging at the charger
            return {self.charge_action_id: "charge"}
        if self.kind == "park":  # a drive to a station, nothing to do there
            return {}
        return {step.action_id: step.action_type for step in self.steps}

    @property
    def pick_index(self) -> int:
        """Route index of the first stop (the pick of a pick → drop order)."""
        return self.steps[0].index if self.steps else self.first_stop

    @pick_index.setter
    def pick_index(self, index: int) -> None:
        if self.steps:
            self.steps[0].index = index
        else:
            self.first_stop = index

    @property
    def pick_action_id(self) -> str:
        return next((s.action_id for s in self.steps if s.action_type == "pick"), "")

    @property
    def drop_action_id(self) -> str:
        return next((s.action_id for s in reversed(self.steps) if s.action_type == "drop"), "")

    def stop_index(self, number: int) -> int:
        """Route index of step `number` (0-based); the last step is always at the route's end."""
        return len(self.route) - 1 if number == len(self.steps) - 1 else self.steps[number].index

    @property
    def stop_indices(self) -> list[int]:
        """Route indices of all stops in order: the goals to plan the route through."""
        if not self.steps:
            return [self.first_stop, len(self.route) - 1]
        return [self.stop_index(number) for number in range(len(self.steps))]

    def move_stops(self, stops: Sequence[int]) -> None:
        """The route was re-planned: stop i is now at route index `stops[i]`."""
        if not self.steps:
            self.first_stop = stops[0] if stops else self.first_stop
        for step, index in zip(self.steps, stops, strict=False):
            step.index = index

    @property
    def charge_action_id(self) -> str:
        return f"{self.vda_order_id}-charge"

    def observe(self, state: vda5050.State) -> list[Progress]:
        """Progress events that `state` reveals (acceptance, actions done, completion, failure)."""
        phase = self.phase
        if phase is Phase.DONE:
            return []
        if phase is Phase.CANCELLING:
            # Also when the vehicle never took the order: its cancelOrder then fails with
            # noOrderToCancel, which ends the cancellation just as well.
            return self._cancel_progress(_statuses(state))
        if state.order_id != self.vda_order_id:
            return self._rejection(state)
        events: list[Progress] = []
        if phase is Phase.SENT:
            self.phase = Phase.RUNNING
            events.append(Progress("started", self.transport_order_id))
        if state.order_update_id > self.confirmed_update:
            self.confirmed_update = state.order_update_id
        if self.awaiting_confirmation and (rejected := self._rejection_error(state)):
            self.phase = Phase.DONE
            return [*events, Progress("failed", self.transport_order_id, {"reason": rejected})]
        actions = state.action_states
        # Unchanged actionStates (Struct equality, in C) hold nothing new: a FAILED one would
        # have ended the order and every FINISHED one is in steps_done already.
        if actions != self._seen_actions:
            statuses = _statuses(state)
            action_steps = self.action_steps
            for action_id, step in action_steps.items():
                status = statuses.get(action_id)
                if status == "FAILED":
                    self.phase = Phase.DONE
                    retries = self.retries.get(action_id, 0)
                    reason = _action_failure(step, retries, state, action_id)
                    failed = Progress("failed", self.transport_order_id, {"reason": reason})
                    return [*events, failed]
                if status == "FINISHED" and action_id not in self.steps_done:
                    self.steps_done.add(action_id)
                    detail = self._step_detail(action_id, step)
                    events.append(Progress("step", self.transport_order_id, detail))
            self._seen_actions = actions
            self._actions_ended = all(statuses.get(a) in TERMINAL for a in action_steps)
        if self._actions_ended and self._is_complete(state):
            self.phase = Phase.DONE
            events.append(Progress("finished", self.transport_order_id))
        return events

    def fatal_error(self, state: vda5050.State) -> Progress | None:
        """A FATAL error ends the order: the vehicle cannot go on without a human."""
        if not state.errors:  # the usual case, once per state
            return None
        fatal = [e for e in state.errors if str(e.error_level) == "FATAL"]
        if not fatal or self.phase is Phase.DONE:
            return None
        self.phase = Phase.DONE
        reason = "; ".join(f"{e.error_type}: {e.error_description or ''}".strip() for e in fatal)
        return Progress("failed", self.transport_order_id, {"reason": f"vehicle error {reason}"})

    def left_automatic(self, state: vda5050.State) -> Progress | None:
        """MANUAL, SERVICE and TEACHIN clear the vehicle's order (REFERENCE I.40, G.37)."""
        mode = str(state.operating_mode)
        # 3.0 INTERVENED keeps the order (REFERENCE I.41); STARTUP clears it (G.37).
        if mode in {"AUTOMATIC", "SEMIAUTOMATIC", "INTERVENED"} or self.phase is Phase.DONE:
            return None
        self.phase = Phase.DONE
        reason = f"vehicle switched to {mode} mode, which clears its order"
        return Progress("failed", self.transport_order_id, {"reason": reason})

    def _step_detail(self, action_id: str, step: str) -> dict[str, str]:
        """What a finished step action reports: its type, node and (0-based) step number."""
        for number, planned in enumerate(self.steps):
            if planned.action_id == action_id:
                node = self.route[self.stop_index(number)]
                return {"step": step, "node": node, "index": str(number)}
        return {"step": step, "node": self.route[-1]}

    def start_cancel(self) -> str:
        self.phase = Phase.CANCELLING
        # Short (23 characters) so it fits small factsheet idLen limits (J.44).
        self.cancel_action_id = f"cancel-{uuid.uuid4().hex[:16]}"
        return self.cancel_action_id

    def _is_complete(self, state: vda5050.State) -> bool:
        """The order's end, but for its actions (`observe` checks those)."""
        return (
            self.fully_released
            and not self.awaiting_confirmation
            and not state.node_states
            and not state.edge_states
            and state.last_node_id == self.route[-1]
        )

    def _cancel_progress(self, statuses: dict[str, str]) -> list[Progress]:
        if self.cancel_action_id and statuses.get(self.cancel_action_id) in TERMINAL:
            self.phase = Phase.DONE
            return [Progress("cancelled", self.transport_order_id)]
        return []

    def _rejection(self, state: vda5050.State) -> list[Progress]:
        if self.phase is Phase.RUNNING:
            # The vehicle took this order and now lists another one or none: it dropped it
            # (e.g. rebooted mid-order). Nothing would ever finish it, so it fails with the
            # reason instead of staying in progress forever (bench/faults link row).
            self.phase = Phase.DONE
            reason = f"vehicle no longer has the order (reports {state.order_id or 'none'!r})"
            return [Progress("failed", self.transport_order_id, {"reason": reason})]
        rejected = self._rejection_error(state) if self.phase is Phase.SENT else None
        if rejected is None:
            return []
        self.phase = Phase.DONE
        return [Progress("failed", self.transport_order_id, {"reason": rejected})]

    def _rejection_error(self, state: vda5050.State) -> str | None:
        """The vehicle's reason if one of its errors references this order (REFERENCE B.15)."""
        for error in state.errors:
            refs = {(r.reference_key, r.reference_value) for r in error.error_references or []}
            if ("orderId", self.vda_order_id) in refs:
                return rejection_reason(error)  # 3.0 types explained (C.18)
        return None


def passed_index(state: vda5050.State) -> int:
    """The route index of the last node the vehicle passed (our sequence ids are 2·index).

    A vehicle that took a new order keeps the previous order's lastNodeSequenceId until it
    passes the new first node; it still lists that node (sequence id 0), and read as progress
    the old id would release the new base too far ahead (and traffic would see the vehicle
    beyond its base when the new route passes the same node at that index: a round trip)."""
    last = state.last_node_sequence_id or 0
    if any(node.sequence_id <= last for node in state.node_states):
        return 0  # not a sequence id of this order: nothing of it passed yet
    return last // 2


def _statuses(state: vda5050.State) -> dict[str, str]:
    """actionStatus by actionId."""
    return {a.action_id: str(a.action_status) for a in state.action_states}


def _action_failure(step: str, retries: int, state: vda5050.State, action_id: str) -> str:
    """`pick action failed after 2 retries: <the vehicle's result>`."""
    reason = f"{step} action failed" + (f" after {retries} retries" if retries else "")
    results = {a.action_id: a.result_description for a in state.action_states}
    result = results.get(action_id)
    return f"{reason}: {result}" if result else reason
