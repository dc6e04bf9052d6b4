"""Execution of one transport order as one VDA 5050 order, tracked from the vehicle's state.

Pure logic without MQTT or the database: `build_order` turns a route into an order message and
`OrderExecution.observe` turns each state into progress events for the flusher to persist.
"""

import enum
import time
import uuid
from dataclasses import dataclass, field

import vda5050
from vda5050.enums import BlockingType

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


class Phase(enum.StrEnum):
    SENT = "SENT"
    RUNNING = "RUNNING"
    CANCELLING = "CANCELLING"
    DONE = "DONE"


@dataclass(frozen=True)
class Progress:
    """Something that happened to a transport order, to be persisted by the flusher."""

    kind: str  # started | step | finished | failed | cancelled | requeued
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

    def start_cancel(self) -> str:
        self.phase = Phase.CANCELLING
        self.cancel_action_id = f"cancel-{uuid.uuid4()}"
        return self.cancel_action_id

    def _is_complete(self, state: vda5050.State, statuses: dict[str, str]) -> bool:
        return (
            not state.node_states
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
        if self.phase is not Phase.SENT:
            return []
        for error in state.errors:
            refs = {(r.reference_key, r.reference_value) for r in error.error_references or []}
            if ("orderId", self.vda_order_id) in refs:
                self.phase = Phase.DONE
                reason = f"rejected by vehicle: {error.error_type} {error.error_description or ''}"
                return [Progress("failed", self.transport_order_id, {"reason": reason.strip()})]
        return []


def build_order(
    execution: OrderExecution,
    layout: LayoutIndex,
    *,
    load_id: str,
    load_type: str,
    pick_station: str,
    drop_station: str,
) -> tuple[list[vda5050.Node], list[vda5050.Edge]]:
    """The order's nodes and edges in traversal order, all released (the base).

    Sequence ids follow REFERENCE A.2: nodes even from 0, edges odd. Pick and drop are HARD
    blocking node actions so the vehicle stands still while handling the load.
    """
    nodes: list[vda5050.Node] = []
    edges: list[vda5050.Edge] = []
    last = len(execution.route) - 1
    for index, node_id in enumerate(execution.route):
        if index:
            previous = execution.route[index - 1]
            edges.append(
                vda5050.Edge(
                    edge_id=layout.edges[(previous, node_id)],
                    sequence_id=2 * index - 1,
                    released=True,
                    start_node_id=previous,
                    end_node_id=node_id,
                    actions=[],
                )
            )
        actions = []
        if index == execution.pick_index:
            actions.append(
                _load_action("pick", execution.pick_action_id, load_id, load_type, pick_station)
            )
        if index == last:
            actions.append(
                _load_action("drop", execution.drop_action_id, load_id, load_type, drop_station)
            )
        place = layout.nodes[node_id]
        nodes.append(
            vda5050.Node(
                node_id=node_id,
                sequence_id=2 * index,
                released=True,
                node_position=vda5050.NodePosition(
                    x=place.x, y=place.y, theta=place.theta, map_id=place.map_id
                ),
                actions=actions,
            )
        )
    return nodes, edges


def _load_action(
    action_type: str, action_id: str, load_id: str, load_type: str, station: str
) -> vda5050.Action:
    parameters = [
        vda5050.ActionParameter(key="stationType", value="floor"),
        vda5050.ActionParameter(key="stationName", value=station),
        vda5050.ActionParameter(key="loadType", value=load_type or "EPAL"),
    ]
    if load_id:
        parameters.append(vda5050.ActionParameter(key="loadId", value=load_id))
    return vda5050.Action(
        action_type=action_type,
        action_id=action_id,
        blocking_type=BlockingType.HARD,
        action_parameters=parameters,
    )
