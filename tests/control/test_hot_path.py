"""The per-state shortcuts of `OrderExecution.observe` and `LiveVehicle.apply_state` (issue 11)
report exactly what a full evaluation of every state would."""

from datetime import UTC, datetime

import vda5050
from control.execution import OrderExecution, Phase, Window
from control.live import InstantActionTrack, LiveVehicle
from control.versions import to_model
from tests.control.fakes import state

ROUTE = ["a", "b", "c", "d"]
PICK, DROP = "TO-7-pick", "TO-7-drop"


def running() -> OrderExecution:
    execution = OrderExecution.plan(
        transport_order_id=7, vda_order_id="TO-7", route=ROUTE, pickup="b"
    )
    execution.sent(0, Window(0, 3, 3))  # the whole route released at once
    return execution


def observe(execution: OrderExecution, **kwargs: object) -> list[tuple[str, dict[str, str]]]:
    payload = state(order_id="TO-7", **kwargs)  # type: ignore[arg-type]
    message = vda5050.decode(vda5050.TopicKind.STATE, payload)
    return [(p.kind, p.detail) for p in execution.observe(message)]


def test_a_finished_step_is_reported_once_though_every_state_repeats_it() -> None:
    execution = running()
    actions = ((PICK, "FINISHED"), (DROP, "WAITING"))

    first = observe(execution, last_node="b", nodes=("c", "d"), actions=actions)
    again = observe(execution, last_node="c", nodes=("d",), actions=actions)

    assert first == [("started", {}), ("step", {"step": "pick", "node": "b", "index": "0"})]
    assert again == []


def test_the_order_finishes_when_the_route_ends_after_the_actions_already_had() -> None:
    execution = running()
    ended = ((PICK, "FINISHED"), (DROP, "FINISHED"))
    observe(execution, last_node="c", nodes=("d",), actions=ended)

    # Same actionStates as before: only the nodes changed.
    events = observe(execution, last_node="d", actions=ended)

    assert events == [("finished", {})]
    assert execution.phase is Phase.DONE


def test_unchanged_actions_that_had_not_ended_never_finish_the_order() -> None:
    execution = running()
    open_actions = ((PICK, "FINISHED"), (DROP, "RUNNING"))
    observe(execution, last_node="c", nodes=("d",), actions=open_actions)

    assert observe(execution, last_node="d", actions=open_actions) == []
    assert observe(execution, last_node="d", actions=((PICK, "FINISHED"), (DROP, "FAILED"))) == [
        ("failed", {"reason": "drop action failed"})
    ]


def test_tracked_instant_actions_follow_the_state_and_untracked_ones_cost_nothing() -> None:
    vehicle = LiveVehicle("sim", "AGV-1", "uagv")
    message = vda5050.decode(
        vda5050.TopicKind.STATE, state(actions=(("ia-1", "FINISHED"), ("other", "FAILED")))
    )

    vehicle.apply_state(message, received_at=datetime.now(UTC))  # nothing tracked yet
    vehicle.track(InstantActionTrack("ia-1", "stateRequest", "SENT"))
    vehicle.needs_flush = vehicle.needs_broadcast = False
    vehicle.apply_state(message, received_at=datetime.now(UTC))

    assert vehicle.instant_actions["ia-1"].status == "FINISHED"
    assert (vehicle.needs_flush, vehicle.needs_broadcast) == (True, True)


def test_only_3_0_messages_are_adapted_to_the_model() -> None:
    v2 = vda5050.decode(vda5050.TopicKind.STATE, state())
    v3 = vda5050.adapt.state_v2_to_v3(v2)

    assert to_model("state", v2) is v2
    assert type(to_model("state", v3)) is vda5050.State
