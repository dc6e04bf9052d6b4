"""3.0 action states: retriable actions (REFERENCE E.27) and clearInstantActions (E.28).

E.27: control sends the order actions of 3.0 vehicles that take retry/skipRetry as
`retriable`; a failure then enters RETRIABLE (2.x model: PAUSED, marked, see
`vda5050.adapt.is_retriable`) and the vehicle waits for the master. Policy for the orders
control drives: `retry` up to `max_retries` times, then `skipRetry`; the action then ends
FAILED and the order fails with the reason "pick action failed after N retries: …" (the master
decides, G.35/G.36, and cancels). `max_retries=None` leaves every decision to the operator,
who sends retry/skipRetry {actionId} as a vehicle command (checked by `control.conflicts`).
A RETRIABLE action of an order control does not drive is left to the operator too.

E.28: 3.0 `instantActionStates` grow until the master sends `clearInstantActions`. Control
sends it once `clear_after` instant actions it sent are terminal in the state, or at once on
INSTANT_ACTION_STATES_FULL, if the factsheet declares it; at most every `CLEAR_EVERY` seconds.
"""

import logging
import time

import vda5050
from control.capabilities import refuse_instant_action
from control.live import InstantActionTrack, LiveVehicle
from control.publisher import ProtocolLimitError, Publisher
from vda5050.adapt import is_retriable

logger = logging.getLogger(__name__)

TERMINAL = frozenset({"FINISHED", "FAILED"})


class ActionStatePolicy:
    """Answers RETRIABLE actions and keeps 3.0 instantActionStates short."""

    CLEAR_EVERY = 10.0  # seconds between two clearInstantActions to one vehicle
    ANSWER_AGAIN = 10.0  # seconds an action may stay RETRIABLE after our answer

    def __init__(
        self, publisher: Publisher, *, max_retries: int | None = 2, clear_after: int = 20
    ) -> None:
        self.publisher = publisher
        self.max_retries = max_retries
        self.clear_after = clear_after

    def on_state(self, vehicle: LiveVehicle, state: vda5050.State) -> None:
        """Called with every applied state of a 3.0 vehicle (after the order was followed)."""
        if vda5050.major_version_of(vehicle.version) != "v3":
            return
        retriable = {a.action_id for a in state.action_states if is_retriable(a)}
        # An action that left RETRIABLE (running again, or FAILED) may be answered again later;
        # one still RETRIABLE long after our answer lost it (QoS 0): it is answered anew.
        now = time.monotonic()
        answered = vehicle.answered_retriable
        for action_id in list(answered):
            if action_id not in retriable or now - answered[action_id] > self.ANSWER_AGAIN:
                del answered[action_id]
        for action_id in sorted(retriable - answered.keys()):
            self._answer(vehicle, state, action_id)
        self._clear(vehicle, state)

    def _answer(self, vehicle: LiveVehicle, state: vda5050.State, action_id: str) -> None:
        execution = vehicle.execution
        if self.max_retries is None or execution is None:
            return  # the operator decides
        step = execution.action_steps.get(action_id)
        if step is None:
            return
        done = execution.retries.get(action_id, 0)
        action_type = "retry" if done < self.max_retries else "skipRetry"
        mode = str(state.operating_mode)
        parameters = {"actionId": action_id}
        if refuse_instant_action(vehicle.capabilities, mode, action_type, parameters):
            return  # e.g. INTERVENED: asked again with a later state
        try:
            sent = self.publisher.instant_action(vehicle, action_type, parameters=parameters)
        except ProtocolLimitError:
            logger.warning("%s for %s does not fit the vehicle's limits", action_type, action_id)
            return
        vehicle.answered_retriable[action_id] = time.monotonic()
        if action_type == "retry":
            execution.retries[action_id] = done + 1
            note = f"automatic retry {done + 1} of {self.max_retries} of {step} {action_id}"
        else:
            note = f"{step} {action_id} still fails after {done} retries: skipped"
        vehicle.track(InstantActionTrack(sent, action_type, "SENT", reason=note))

    def _clear(self, vehicle: LiveVehicle, state: vda5050.State) -> None:
        capabilities = vehicle.capabilities
        if capabilities is None or not capabilities.declares_instant("clearInstantActions"):
            return
        now = time.monotonic()
        if now - vehicle.cleared_at < self.CLEAR_EVERY:
            return
        full = any(str(e.error_type) == "INSTANT_ACTION_STATES_FULL" for e in state.errors)
        ours = sum(
            1
            for a in state.action_states
            if a.action_id in vehicle.sent_instant and str(a.action_status) in TERMINAL
        )
        if not full and ours < self.clear_after:
            return
        mode = str(state.operating_mode)
        if refuse_instant_action(capabilities, mode, "clearInstantActions", {}):
            return
        try:
            self.publisher.instant_action(vehicle, "clearInstantActions")
        except ProtocolLimitError:
            return
        vehicle.cleared_at = now
        self.publisher.counters["cleared_instant_actions"] += 1
