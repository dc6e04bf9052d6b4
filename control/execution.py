"""Execution of one transport order as one VDA 5050 order, tracked from the vehicle's state.

Pure logic without MQTT or the database: `build_order` turns a route into an order message and
`OrderExecution.observe` turns each state into progress events for the flusher to persist.
"""

import enum
import time
import uuid
from dataclasses import dataclass, field

import vda5050

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


@dataclass
class OrderExecution:
    """One transport order being driven by one vehicle as VDA 5050 order `vda_order_id`."""

    transport_order_id: int
    vda_order_id: str
    route: list[str]
    pick_index: int
    pick_action_id: str
    drop_action_id: str
    phase: Phase = Phase.SENT
    sent_monotonic: float = field(default_factory=time.monotonic)
    cancel_action_id: str | None = None
    steps_done: set[str] = field(default_factory=set)
    released_until: int = -1  # route index of the last base node sent
    update_id: int = -1  # orderUpdateId of the latest message sent
    confirmed_update: int = -1  # latest orderUpdateId the vehicle's state showed
    attempts: int = 0  # sends of the latest message (resends are identical)
    window: Window | None = None  # what the latest message carried

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
        cls, *, transport_order_id: int, vda_order_id: str, route: list[str], pickup: str
    ) -> "OrderExecution":
        return cls(
            transport_order_id=transport_order_id,
            vda_order_id=vda_order_id,
            route=route,
            pick_index=route.index(pickup),
            # Derived from the order id, so a restarted control recognises them.
            pick_action_id=f"{vda_order_id}-pick",
            drop_action_id=f"{vda_order_id}-drop",
        )

    @property
    def action_steps(self) -> dict[str, str]:
        return {self.pick_action_id: "pick", self.drop_action_id: "drop"}

    def observe(self, state: vda5050.State) -> list[Progress]:
        """Progress events that `state` reveals (acceptance, actions done, completion, failure)."""
        if self.phase is Phase.DONE:
            return []
        statuses = {a.action_id: str(a.action_status) for a in state.action_states}
        if self.phase is Phase.CANCELLING:
            # Also when the vehicle never took the order: its cancelOrder then fails with
            # noOrderToCancel, which ends the cancellation just as well.
            return self._cancel_progress(statuses)
        if state.order_id != self.vda_order_id:
            return self._rejection(state)
        events: list[Progress] = []
        if self.phase is Phase.SENT:
            self.phase = Phase.RUNNING
            events.append(Progress("started", self.transport_order_id))
        self.confirmed_update = max(self.confirmed_update, state.order_update_id)
        if self.awaiting_confirmation and (rejected := self._rejection_error(state)):
            self.phase = Phase.DONE
            return [*events, Progress("failed", self.transport_order_id, {"reason": rejected})]
        for action_id, step in self.action_steps.items():
            status = statuses.get(action_id)
            if status == "FAILED":
                self.phase = Phase.DONE
                return [
                    *events,
                    Progress(
                        "failed", self.transport_order_id, {"reason": f"{step} action failed"}
                    ),
                ]
            if status == "FINISHED" and step not in self.steps_done:
                self.steps_done.add(step)
                node = self.route[self.pick_index if step == "pick" else -1]
                events.append(
                    Progress("step", self.transport_order_id, {"step": step, "node": node})
                )
        if self._is_complete(state, statuses):
            self.phase = Phase.DONE
            events.append(Progress("finished", self.transport_order_id))
        return events

    def fatal_error(self, state: vda5050.State) -> Progress | None:
        """A FATAL error ends the order: the vehicle cannot go on without a human."""
        fatal = [e for e in state.errors if str(e.error_level) == "FATAL"]
        if not fatal or self.phase is Phase.DONE:
            return None
        self.phase = Phase.DONE
        reason = "; ".join(f"{e.error_type}: {e.error_description or ''}".strip() for e in fatal)
        return Progress("failed", self.transport_order_id, {"reason": f"vehicle error {reason}"})

    def left_automatic(self, state: vda5050.State) -> Progress | None:
        """MANUAL, SERVICE and TEACHIN clear the vehicle's order (REFERENCE I.40, G.37)."""
        mode = str(state.operating_mode)
        if mode in {"AUTOMATIC", "SEMIAUTOMATIC"} or self.phase is Phase.DONE:
            return None
        self.phase = Phase.DONE
        reason = f"vehicle switched to {mode} mode, which clears its order"
        return Progress("failed", self.transport_order_id, {"reason": reason})

    def start_cancel(self) -> str:
        self.phase = Phase.CANCELLING
        self.cancel_action_id = f"cancel-{uuid.uuid4()}"
        return self.cancel_action_id

    def _is_complete(self, state: vda5050.State, statuses: dict[str, str]) -> bool:
        return (
            self.fully_released
            and not self.awaiting_confirmation
            and not state.node_states
            and not state.edge_states
            and all(statuses.get(a) in TERMINAL for a in self.action_steps)
            and state.last_node_id == self.route[-1]
        )

    def _cancel_progress(self, statuses: dict[str, str]) -> list[Progress]:
        if self.cancel_action_id and statuses.get(self.cancel_action_id) in TERMINAL:
            self.phase = Phase.DONE
            return [Progress("cancelled", self.transport_order_id)]
        return []

    def _rejection(self, state: vda5050.State) -> list[Progress]:
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
                text = f"{error.error_type} {error.error_description or ''}".strip()
                return f"rejected by vehicle: {text}"
        return None
