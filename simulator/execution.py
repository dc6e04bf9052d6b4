"""Execution of order (node) actions and instant actions for one virtual vehicle.

Node actions run in list order once their node is reached and honour their blockingType
(REFERENCE §3 E.24): NONE runs in parallel and lets the vehicle drive, SINGLE (3.0) runs
alone but lets the vehicle drive, SOFT runs in parallel but stops driving, HARD runs alone
and stops driving. Each status change
(WAITING → INITIALIZING → RUNNING → FINISHED/FAILED) happens on its own tick so that every
intermediate status can appear in at least one published state.

Instant actions other than ``cancelOrder`` take effect immediately when received. In
MANUAL, SERVICE and TEACHIN mode only the read-only stateRequest, factsheetRequest and
logReport are executed; every other instant action fails (REFERENCE §3 I.40).

3.0 differences: instant actions keep their states across new orders until
``clearInstantActions`` (REFERENCE §3 E.28), must use blockingType NONE and, if they cannot
be executed, also raise an INVALID_INSTANT_ACTION warning; ``cancelOrder`` may name the
``orderId`` to cancel (a different one fails with NO_ORDER_TO_CANCEL). A failing order
action sent ``retriable`` enters RETRIABLE (REFERENCE §3 E.27; the 2.x model carries it as a
marked PAUSED) and keeps its place, and blocking, until the master's ``retry`` (run it again)
or ``skipRetry`` (FAILED, the order goes on); cancelOrder fails it like a WAITING one.
"""

from __future__ import annotations

import logging
import math
from collections.abc import Iterable
from typing import TYPE_CHECKING

from simulator import messages
from simulator.actions import CATALOGUE, ActionRun, check_action
from simulator.intake import ORDER_MODES
from simulator.maps import MAP_ACTIONS
from vda5050 import Action, Load, ParameterValue, action_params
from vda5050.enums import ActionScope, ActionStatus, BlockingType

if TYPE_CHECKING:
    from simulator.orders import Step
    from simulator.vehicle import VirtualVehicle

log = logging.getLogger(__name__)

#: 3.0: instantActionStates at which INSTANT_ACTION_STATES_FULL (URGENT) is reported, and
#: the most kept (the factsheet's maximum; beyond it the oldest finished ones are dropped).
INSTANT_STATES_FULL = 100
INSTANT_STATES_MAX = 200

_STOPPING = (BlockingType.SOFT, BlockingType.HARD)
_EXCLUSIVE = frozenset({"HARD", "SINGLE"})  # no other action in parallel
_READ_ONLY = frozenset({"stateRequest", "factsheetRequest", "logReport"})


class ActionExecutor:
    """Tracks ``actionStates`` and runs actions against its vehicle."""

    def __init__(self, vehicle: VirtualVehicle) -> None:
        self._vehicle = vehicle
        self._runs: dict[str, ActionRun] = {}
        self._queue: list[ActionRun] = []  # triggered node actions, in execution order
        self._cancels: list[ActionRun] = []  # cancelOrder actions waiting for the stop

    # ------------------------------------------------------------------ queries
    def reported(self) -> list[ActionRun]:
        """Runs in the order they appear in ``actionStates``."""
        return list(self._runs.values())

    def get(self, action_id: str) -> ActionRun | None:
        """The run of ``action_id``, if known."""
        return self._runs.get(action_id)

    @property
    def instant_ids(self) -> frozenset[str]:
        """Ids of the reported instant actions (3.0 lists them in instantActionStates)."""
        return frozenset(k for k, run in self._runs.items() if run.node_key is None)

    @property
    def all_terminal(self) -> bool:
        """Every reported action is FINISHED or FAILED."""
        return all(run.terminal for run in self._runs.values())

    @property
    def order_busy(self) -> bool:
        """Some order action is not terminal yet."""
        return any(run.node_key is not None and not run.terminal for run in self._runs.values())

    @property
    def blocks_driving(self) -> bool:
        """A triggered SOFT/HARD action is not finished, so the vehicle must stand still."""
        return any(
            not run.terminal and run.action.blocking_type in _STOPPING for run in self._queue
        )

    # ------------------------------------------------------------------ order bookkeeping
    def reset_for_new_order(self, steps: Iterable[Step]) -> None:
        """2.x: actionStates restart with a new order; unfinished instant actions stay.
        3.0: every instant action stays until clearInstantActions."""
        keep_finished = self._vehicle.config.major >= 3
        self._runs = {
            k: r
            for k, r in self._runs.items()
            if r.node_key is None and (keep_finished or not r.terminal)
        }
        self._queue = []
        self._register(steps)

    def replace_horizon(self, dropped: Iterable[Step], added: Iterable[Step]) -> None:
        """Order update: forget the old horizon's (still WAITING) actions, add the new ones."""
        for step in dropped:
            for action in step.node.actions:
                run = self._runs.get(action.action_id)
                if run is not None and run.status is ActionStatus.WAITING:
                    del self._runs[action.action_id]
        self._register(added)

    def _register(self, steps: Iterable[Step]) -> None:
        for step in steps:
            for action in step.node.actions:
                self._runs[action.action_id] = ActionRun(action=action, node_key=step.key)

    def abort_order(self, reason: str) -> None:
        """The order is cleared (operating mode): every unfinished order action fails."""
        for run in self._runs.values():
            if run.node_key is not None and not run.terminal:
                run.fail(reason)
        self._queue = [run for run in self._queue if not run.terminal]

    def trigger_node(self, key: tuple[str, int]) -> None:
        """The vehicle reached node ``key``: queue its WAITING actions in list order."""
        self._queue += [
            run
            for run in self._runs.values()
            if run.node_key == key and run.status is ActionStatus.WAITING
        ]

    # ------------------------------------------------------------------ simulation
    def advance(self, sim_dt: float) -> None:
        """Move every triggered action on by at most one status per tick."""
        exclusive_active = any_active = False
        for run in self._queue:
            exclusive = run.action.blocking_type in _EXCLUSIVE
            if run.status is ActionStatus.WAITING:
                # List order is execution order: a blocked action blocks all after it.
                if exclusive_active or (exclusive and any_active):
                    break
                run.status = ActionStatus.INITIALIZING
                self._vehicle.mark_state_due()
            elif run.status is ActionStatus.INITIALIZING:
                run.status = ActionStatus.RUNNING
                run.remaining = CATALOGUE[run.action.action_type].duration
                self._vehicle.mark_state_due()
            elif run.status is ActionStatus.RUNNING:
                run.remaining -= sim_dt
                if run.remaining <= 0.0:
                    self._finish(run)
            if run.active or run.retriable:  # a RETRIABLE action still holds its place
                any_active = True
                exclusive_active = exclusive_active or exclusive
        self._queue = [run for run in self._queue if not run.terminal]

    def _finish(self, run: ActionRun) -> None:
        failure = self._effect(run.action)
        if failure is None:
            run.status = ActionStatus.FINISHED
        elif run.node_key is not None and getattr(run.action, "retriable", False):
            run.hold_for_retry(failure)  # 3.0 only: 2.x actions never carry the flag
        else:
            run.fail(failure)
        self._vehicle.mark_state_due()

    def check_cancel_done(self) -> None:
        """cancelOrder turns FINISHED once the vehicle stands still with nothing running."""
        if not self._cancels:
            return
        vehicle = self._vehicle
        if vehicle.pending or vehicle.driving or any(not r.terminal for r in self._queue):
            return
        for run in self._cancels:
            run.status = ActionStatus.FINISHED
        self._cancels = []
        vehicle.mark_state_due()

    # ------------------------------------------------------------------ instant actions
    def run_instant(self, action: Action) -> None:
        """Execute one instant action (immediately, except cancelOrder)."""
        if action.action_id in self._runs:
            return  # a resend of an action we already know: do not execute it twice
        idle = self._vehicle.idle  # before this action itself shows up as not terminal
        run = ActionRun(action=action)
        self._runs[action.action_id] = run
        vehicle = self._vehicle
        v3 = vehicle.config.major >= 3
        if v3:
            self._trim_instant_states()
        problem = check_action(action, ActionScope.INSTANT, vehicle.config.major)
        if problem is None and v3 and action.blocking_type != BlockingType.NONE:
            problem = f"instant action blockingType must be NONE, got {action.blocking_type}"
        if problem is not None:
            run.fail(problem)
            if v3:
                vehicle.add_invalid_instant_action(action.action_id, problem)
            return
        kind = action.action_type
        if vehicle.operating_mode not in ORDER_MODES and kind not in _READ_ONLY:
            run.fail(f"operating mode {vehicle.operating_mode} accepts no instant actions")
            return
        if kind == "cancelOrder":
            self._cancel(run)
            return
        if kind == "startPause":
            vehicle.paused = True
        elif kind == "stopPause":
            vehicle.paused = False
        elif kind == "stateRequest":
            vehicle.mark_state_due()
        elif kind == "factsheetRequest":
            vehicle.factsheet_due = True
        elif kind == "logReport":
            reason = action_params(action).get("reason")
            log.info("%s: logReport: %s", vehicle.config.serial_number, reason)
        elif kind in {"retry", "skipRetry"}:
            problem = self._retry(kind, action_params(action).get("actionId"))
            if problem is not None:
                run.fail(problem)
                vehicle.add_invalid_instant_action(action.action_id, problem)
                return
        elif kind == "clearInstantActions":
            self._runs = {
                k: r for k, r in self._runs.items() if r.node_key is not None or not r.terminal
            }
        elif kind == "initPosition" and not idle:
            run.fail("initPosition is only accepted while the vehicle is idle")
            return
        else:
            failure = self._effect(action)
            if failure is not None:
                run.fail(failure)
                return
        run.status = ActionStatus.FINISHED

    def _retry(self, kind: str, action_id: object) -> str | None:
        """retry runs a RETRIABLE action again, skipRetry fails it; the problem, if any."""
        target = self._runs.get(action_id) if isinstance(action_id, str) else None
        if target is None or not target.retriable:
            return f"{kind}: action {action_id!r} is not RETRIABLE"
        if kind == "retry":
            target.status, target.result = ActionStatus.INITIALIZING, None
        else:
            target.fail((target.result or "").removeprefix("RETRIABLE: ") or "retry skipped")
        return None

    def _trim_instant_states(self) -> None:
        """3.0: keep at most INSTANT_STATES_MAX instant action states (oldest finished go)."""
        instant = [k for k, r in self._runs.items() if r.node_key is None]
        excess = len(instant) - INSTANT_STATES_MAX
        for key in instant:
            if excess <= 0:
                break
            if self._runs[key].terminal:
                del self._runs[key]
                excess -= 1

    def _cancel(self, run: ActionRun) -> None:
        vehicle = self._vehicle
        named = action_params(run.action).get("orderId") if vehicle.config.major >= 3 else None
        if not vehicle.has_order or (named is not None and named != vehicle.order_id):
            run.fail("no order to cancel")
            vehicle.add_no_order_to_cancel(run.action_id)
            return
        for other in self._runs.values():
            waiting = other.status is ActionStatus.WAITING or other.retriable
            if other.node_key is not None and waiting:
                other.fail("order cancelled")
        self._queue = [r for r in self._queue if not r.terminal]
        vehicle.cancel_order()
        run.status = ActionStatus.RUNNING
        self._cancels.append(run)

    # ------------------------------------------------------------------ effects
    def _effect(self, action: Action) -> str | None:
        """Apply an action unless the misbehaviour makes it fail; failure reason or None."""
        vehicle = self._vehicle
        if vehicle.saboteur.action_fails(action.action_type):
            vehicle.report_action_failure(action.action_id, action.action_type)
            return f"{action.action_type} failed (simulated misbehaviour)"
        return self._apply(action)

    def _apply(self, action: Action) -> str | None:
        """Carry out the effect of a finished action; returns a failure reason or None."""
        vehicle = self._vehicle
        params = action_params(action)
        kind = action.action_type
        if kind == "pick":
            if vehicle.loads:
                return "already carrying a load"
            vehicle.loads = [
                Load(
                    load_id=_opt_str(params.get("loadId")),
                    load_type=_opt_str(params.get("loadType")),
                    load_position=_opt_str(params.get("lhd")),
                )
            ]
        elif kind == "drop":
            if not vehicle.loads:
                return "no load to drop"
            vehicle.loads = []
        elif kind == "startCharging":
            if vehicle.driving:
                return "cannot start charging while driving"
            vehicle.charging = True
        elif kind == "stopCharging":
            vehicle.charging = False
        elif kind == "initPosition":
            return self._init_position(params)
        elif kind == "detectObject":
            pass  # nothing to detect in a simulation; it just takes its time
        elif kind in MAP_ACTIONS:
            if kind != "enableZoneSet" and not messages.is_v21(vehicle.config.version):
                return f"{kind} needs protocol 2.1 or later"
            failure = vehicle.map_store.apply(kind, params)
            if failure is not None:
                return failure
        else:
            return f"actionType {kind!r} has no effect in the simulator"
        vehicle.mark_state_due()
        return None

    def _init_position(self, params: dict[str, ParameterValue]) -> str | None:
        coords = [params.get(key) for key in ("x", "y", "theta")]
        numbers = [
            float(v)
            for v in coords
            if isinstance(v, int | float) and not isinstance(v, bool) and math.isfinite(v)
        ]
        if len(numbers) != 3:
            return "x, y and theta must be finite numbers"
        map_id, node_id = params.get("mapId"), params.get("lastNodeId")
        if not isinstance(map_id, str) or map_id not in self._vehicle.maps:
            return f"unknown mapId {map_id!r}"
        if not isinstance(node_id, str):
            return "lastNodeId must be a string"
        self._vehicle.init_position(numbers[0], numbers[1], numbers[2], map_id, node_id)
        return None


def _opt_str(value: object) -> str | None:
    return None if value is None else str(value)
