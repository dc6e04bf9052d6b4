"""3.0-only master-control rules: retriable actions (E.27), instantActionStates (E.28), the
INTERVENED and STARTUP modes (I.41) and the predefined rejection types (C.18).

The vehicle here speaks 3.0.0; every message the controller publishes is validated against
the 3.0 schemas (fixture `sent`, as in test_controller.py)."""

import json
from collections.abc import Iterator

import pytest

import vda5050
from control.capabilities import Capabilities
from control.controller import Controller
from control.rejections import V3_REASONS
from tests.control import fakes
from tests.control.fakes import FakeStore, order, state
from tests.control.test_controller import Published, instant_actions_in, orders_in
from vda5050.enums import ActionScope, ValueDataType


@pytest.fixture(autouse=True)
def version_3() -> Iterator[None]:
    previous = fakes.PROTOCOL["version"]
    fakes.PROTOCOL["version"] = "3.0.0"
    yield
    fakes.PROTOCOL["version"] = previous


@pytest.fixture
def sent() -> Iterator[Published]:
    published = Published()
    published.problems = []
    yield published
    assert published.problems == []


@pytest.fixture
def controller(sent) -> Iterator[Controller]:
    ctrl = Controller(store=FakeStore(), interface_name="uagv", publish=sent)
    ctrl.load()
    yield ctrl
    assert ctrl.counters["handler_errors"] == 0


def instant(action_type: str, *, parameter: str | None = None) -> vda5050.AgvAction:
    return vda5050.AgvAction(
        action_type=action_type,
        action_scopes=[ActionScope.INSTANT],
        action_parameters=None
        if parameter is None
        else [vda5050.ActionParameterSpec(key=parameter, value_data_type=ValueDataType.STRING)],
    )


RETRYING = Capabilities(
    {
        "retry": instant("retry", parameter="actionId"),
        "skipRetry": instant("skipRetry", parameter="actionId"),
        "clearInstantActions": instant("clearInstantActions"),
    }
)


def v3_state(
    *, retriable: tuple[str, ...] = (), mode: str | None = None, **kwargs: object
) -> bytes:
    """A 3.0 state (fakes.state) with the actions in `retriable` RETRIABLE."""
    data = json.loads(state(**kwargs))  # type: ignore[arg-type]
    for action in data["actionStates"] + data["instantActionStates"]:
        if action["actionId"] in retriable:
            action["actionStatus"] = "RETRIABLE"
            action["actionResult"] = "gripper slipped"
    if mode is not None:
        data["operatingMode"] = mode
    return json.dumps(data).encode()


def running(controller: Controller, capabilities: Capabilities | None = RETRYING) -> None:
    controller.handle_message(fakes.topic(), state(header_id=1))
    controller.fleet.by_pk(1).capabilities = capabilities
    controller.sync([order()])
    controller.handle_message(
        fakes.topic(),
        state(header_id=2, order_id="TO-7", nodes=("b", "c", "d"), actions=_waiting()),
    )


def _waiting(pick: str = "WAITING") -> tuple[tuple[str, str], ...]:
    return (("TO-7-pick", pick), ("TO-7-drop", "WAITING"))


def retries_sent(sent: Published) -> list[tuple[str, str]]:
    return [
        (a["actionType"], a["actionParameters"][0]["value"])
        for t, m in sent
        if t.endswith("/instantActions")
        for a in m["actions"]
        if a["actionType"] in {"retry", "skipRetry"}
    ]


def test_E27_order_actions_go_out_retriable_only_to_vehicles_that_take_retry(
    controller, sent
) -> None:
    running(controller)
    (message,) = orders_in(sent)
    actions = [a for n in message["nodes"] for a in n["actions"]]
    assert [(a["actionType"], a.get("retriable")) for a in actions] == [
        ("pick", True),
        ("drop", True),
    ]


def test_E27_without_retry_in_the_factsheet_no_action_is_retriable(controller, sent) -> None:
    running(controller, Capabilities({}))
    (message,) = orders_in(sent)
    assert all("retriable" not in a for n in message["nodes"] for a in n["actions"])


def test_E27_a_retriable_action_is_retried_up_to_the_limit_then_skipped_and_the_order_fails(
    controller, sent
) -> None:
    running(controller)
    topic = fakes.topic()
    header = iter(range(3, 100))

    def report(pick: str, retriable: bool = False) -> None:
        controller.handle_message(
            topic,
            v3_state(
                header_id=next(header),
                order_id="TO-7",
                last_node="b",
                nodes=("c", "d"),
                actions=_waiting(pick),
                retriable=("TO-7-pick",) if retriable else (),
            ),
        )

    report("FAILED", retriable=True)
    report("FAILED", retriable=True)  # still RETRIABLE before the vehicle read our retry
    report("RUNNING")
    report("FAILED", retriable=True)
    report("RUNNING")
    report("FAILED", retriable=True)
    assert retries_sent(sent) == [
        ("retry", "TO-7-pick"),
        ("retry", "TO-7-pick"),
        ("skipRetry", "TO-7-pick"),
    ]
    report("FAILED")
    controller.flush()

    failed = controller.store.batches[-1].progress[-1]
    assert failed.kind == "failed"
    assert failed.detail["reason"].startswith("pick action failed after 2 retries")
    assert instant_actions_in(sent)[-1] == "cancelOrder"
    notes = [t.reason for t in controller.fleet.by_pk(1).instant_actions.values()]
    assert "automatic retry 1 of 2 of pick TO-7-pick" in notes


def test_E27_a_retried_action_that_then_finishes_lets_the_order_finish(controller, sent) -> None:
    running(controller)
    topic = fakes.topic()
    controller.handle_message(
        topic,
        v3_state(
            header_id=3,
            order_id="TO-7",
            last_node="b",
            nodes=("c", "d"),
            actions=_waiting("FAILED"),
            retriable=("TO-7-pick",),
        ),
    )
    controller.handle_message(
        topic,
        state(
            header_id=4,
            order_id="TO-7",
            last_node="d",
            actions=(("TO-7-pick", "FINISHED"), ("TO-7-drop", "FINISHED")),
        ),
    )
    controller.flush()

    assert retries_sent(sent) == [("retry", "TO-7-pick")]
    assert controller.store.batches[-1].progress[-1].kind == "finished"


def test_E27_the_operator_retries_or_skips_only_a_retriable_action(controller, sent) -> None:
    controller.action_states.max_retries = None  # the operator decides
    running(controller)
    controller.handle_message(
        fakes.topic(),
        v3_state(
            header_id=3,
            order_id="TO-7",
            last_node="b",
            nodes=("c", "d"),
            actions=_waiting("FAILED"),
            retriable=("TO-7-pick",),
        ),
    )
    assert retries_sent(sent) == []

    for action_id, request in (("TO-7-drop", "r-1"), ("TO-7-pick", "r-2")):
        controller.execute(
            {
                "kind": "vehicle.instant_action",
                "vehicle": 1,
                "action_type": "skipRetry",
                "parameters": {"actionId": action_id},
                "request": request,
            }
        )

    outcomes = {o.request: (o.status, o.reason) for o in controller.fleet.by_pk(1).command_outcomes}
    assert outcomes == {
        "r-1": ("REFUSED", "action TO-7-drop is not RETRIABLE"),
        "r-2": ("SENT", ""),
    }
    assert retries_sent(sent) == [("skipRetry", "TO-7-pick")]


def test_E28_clear_instant_actions_once_enough_of_ours_are_terminal(controller, sent) -> None:
    controller.action_states.clear_after = 2
    controller.handle_message(fakes.topic(), state(header_id=1))
    controller.fleet.by_pk(1).capabilities = RETRYING
    controller.execute({"kind": "vehicle.pause", "vehicle": 1})
    controller.execute({"kind": "vehicle.resume", "vehicle": 1})
    ids = [a["actionId"] for t, m in sent if t.endswith("/instantActions") for a in m["actions"]]
    pause, resume = ids[-2:]

    controller.handle_message(fakes.topic(), state(header_id=2, actions=((pause, "FINISHED"),)))
    before = instant_actions_in(sent).count("clearInstantActions")
    both = ((pause, "FINISHED"), (resume, "FINISHED"))
    controller.handle_message(fakes.topic(), state(header_id=3, actions=both))
    controller.handle_message(fakes.topic(), state(header_id=4, actions=both))

    assert before == 0
    assert instant_actions_in(sent).count("clearInstantActions") == 1  # not again at once


def test_E28_instant_action_states_full_clears_at_once(controller, sent) -> None:
    controller.handle_message(fakes.topic(), state(header_id=1))
    controller.fleet.by_pk(1).capabilities = RETRYING
    data = json.loads(state(header_id=2))
    data["errors"] = [{"errorType": "INSTANT_ACTION_STATES_FULL", "errorLevel": "URGENT"}]

    controller.handle_message(fakes.topic(), json.dumps(data).encode())

    assert instant_actions_in(sent)[-1] == "clearInstantActions"


def test_I41_intervened_takes_a_new_order_but_no_instant_action_besides_cancel(
    controller, sent
) -> None:
    controller.handle_message(fakes.topic(), v3_state(header_id=1, mode="INTERVENED"))

    controller.sync([order()])
    controller.execute({"kind": "vehicle.pause", "vehicle": 1, "request": "p"})

    assert len(orders_in(sent)) == 1
    (outcome,) = controller.fleet.by_pk(1).command_outcomes
    assert outcome.status == "REFUSED"
    assert "INTERVENED" in outcome.reason


def test_I41_intervened_keeps_the_running_order_and_startup_clears_it(controller) -> None:
    running(controller)
    topic = fakes.topic()
    controller.handle_message(
        topic, v3_state(header_id=3, order_id="TO-7", nodes=("b", "c", "d"), mode="INTERVENED")
    )
    kept = controller.fleet.by_pk(1).execution is not None

    controller.handle_message(topic, v3_state(header_id=4, order_id="TO-7", mode="STARTUP"))
    controller.flush()

    assert kept
    assert controller.store.batches[-1].progress[-1].detail == {
        "reason": "vehicle switched to STARTUP mode, which clears its order"
    }


def test_I41_startup_takes_no_order(controller, sent) -> None:
    controller.handle_message(fakes.topic(), v3_state(header_id=1, mode="STARTUP"))
    controller.sync([order()])
    assert orders_in(sent) == []


@pytest.mark.parametrize("error_type", sorted(V3_REASONS))
def test_C18_each_3_0_rejection_type_gives_its_own_reason(controller, error_type) -> None:
    controller.handle_message(fakes.topic(), state(header_id=1))
    controller.sync([order()])
    data = json.loads(state(header_id=2))
    data["errors"] = [
        {
            "errorType": error_type,
            "errorLevel": "WARNING",
            "errorDescription": "as reported",
            "errorReferences": [{"referenceKey": "orderId", "referenceValue": "TO-7"}],
        }
    ]

    controller.handle_message(fakes.topic(), json.dumps(data).encode())
    controller.flush()

    failed = controller.store.batches[-1].progress[-1]
    assert failed.kind == "failed"
    assert failed.detail["reason"] == (
        f"rejected by vehicle: {error_type} as reported ({V3_REASONS[error_type]})"
    )


def test_C18_the_reasons_of_different_types_differ() -> None:
    distinct = {v for k, v in V3_REASONS.items() if k != "INVALID_ORDER"}  # its enum spelling
    assert len(distinct) == len(V3_REASONS) - 1


def test_E27_an_answer_the_vehicle_never_saw_is_sent_again(controller, sent) -> None:
    running(controller)
    retriable = {
        "order_id": "TO-7",
        "last_node": "b",
        "nodes": ("c", "d"),
        "actions": _waiting("FAILED"),
        "retriable": ("TO-7-pick",),
    }
    controller.handle_message(fakes.topic(), v3_state(header_id=3, **retriable))
    controller.handle_message(fakes.topic(), v3_state(header_id=4, **retriable))
    answered = controller.fleet.by_pk(1).answered_retriable
    answered["TO-7-pick"] -= controller.action_states.ANSWER_AGAIN + 1  # lost on the way

    controller.handle_message(fakes.topic(), v3_state(header_id=5, **retriable))

    assert retries_sent(sent) == [("retry", "TO-7-pick"), ("retry", "TO-7-pick")]
