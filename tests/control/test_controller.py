import json

import pytest

from control.controller import Controller
from control.execution import Phase
from tests.control.fakes import FakeStore, order, state

STATE_TOPIC = "uagv/v2/sim/AGV-1/state"


@pytest.fixture
def sent() -> list[tuple[str, dict]]:
    return []


@pytest.fixture
def controller(sent) -> Controller:
    ctrl = Controller(
        store=FakeStore(),
        interface_name="uagv",
        publish=lambda topic, payload, qos: sent.append((topic, json.loads(payload))),
    )
    ctrl.load()
    return ctrl


def test_an_idle_available_vehicle_gets_the_assigned_order(controller, sent) -> None:
    controller.handle_message(STATE_TOPIC, state(last_node="a"))

    controller.sync([order()])

    topic, message = sent[0]
    assert topic == "uagv/v2/sim/AGV-1/order"
    assert message["orderId"] == "TO-7"
    assert message["orderUpdateId"] == 0
    assert [n["nodeId"] for n in message["nodes"]] == ["a", "b", "c", "d"]
    assert message["headerId"] == 0


def test_order_is_not_sent_before_the_vehicle_state_is_known(controller, sent) -> None:
    controller.sync([order()])
    assert sent == []


def test_order_is_not_sent_to_a_busy_vehicle(controller, sent) -> None:
    controller.handle_message(STATE_TOPIC, state(order_id="OTHER", nodes=("x",)))
    controller.sync([order()])
    assert sent == []


def test_progress_from_state_goes_to_the_flusher_in_order(controller) -> None:
    controller.handle_message(STATE_TOPIC, state(last_node="a"))
    controller.sync([order()])
    vehicle = controller.fleet.by_pk(1)
    ids = (vehicle.execution.pick_action_id, vehicle.execution.drop_action_id)

    controller.handle_message(
        STATE_TOPIC,
        state(
            header_id=2,
            order_id="TO-7",
            nodes=("b", "c", "d"),
            actions=((ids[0], "WAITING"), (ids[1], "WAITING")),
        ),
    )
    controller.handle_message(
        STATE_TOPIC,
        state(
            header_id=3,
            order_id="TO-7",
            last_node="b",
            nodes=("c", "d"),
            actions=((ids[0], "FINISHED"), (ids[1], "WAITING")),
        ),
    )
    controller.handle_message(
        STATE_TOPIC,
        state(
            header_id=4,
            order_id="TO-7",
            last_node="d",
            actions=((ids[0], "FINISHED"), (ids[1], "FINISHED")),
        ),
    )
    controller.flush()

    batch = controller.store.batches[-1]
    assert [(p.kind, p.detail.get("step")) for p in batch.progress] == [
        ("started", None),
        ("step", "pick"),
        ("step", "drop"),
        ("finished", None),
    ]
    assert vehicle.execution is None
    assert batch.snapshots[0]["last_node_id"] == "d"


def test_a_rejected_order_fails_with_the_vehicle_error(controller) -> None:
    controller.handle_message(STATE_TOPIC, state())
    controller.sync([order()])

    controller.handle_message(
        STATE_TOPIC, state(header_id=2, errors=(("validationError", "WARNING", "TO-7"),))
    )
    controller.flush()

    failed = controller.store.batches[-1].progress[-1]
    assert failed.kind == "failed"
    assert "validationError" in failed.detail["reason"]


def test_restarted_control_adopts_a_running_order_without_resending(controller, sent) -> None:
    controller.handle_message(
        STATE_TOPIC,
        state(
            order_id="TO-7",
            last_node="b",
            nodes=("c", "d"),
            driving=True,
            actions=(("TO-7-pick", "FINISHED"), ("TO-7-drop", "WAITING")),
        ),
    )

    controller.sync([order()])

    assert sent == []
    assert controller.fleet.by_pk(1).execution.phase is Phase.RUNNING


def test_cancel_request_sends_cancel_order_and_completes_when_it_finishes(controller, sent) -> None:
    controller.handle_message(STATE_TOPIC, state())
    controller.sync([order()])
    controller.handle_message(STATE_TOPIC, state(header_id=2, order_id="TO-7", nodes=("b",)))

    controller.sync([order(cancel_requested=True)])
    cancel = sent[-1][1]["actions"][0]
    controller.handle_message(
        STATE_TOPIC,
        state(header_id=3, order_id="TO-7", actions=((cancel["actionId"], "FINISHED"),)),
    )
    controller.flush()

    assert sent[-1][0].endswith("/instantActions")
    assert cancel["actionType"] == "cancelOrder"
    assert controller.store.batches[-1].progress[-1].kind == "cancelled"


@pytest.mark.parametrize(
    "payload",
    [b"", b"{", b"[" * 100_000, b'{"headerId": NaN}', b"\xff\xfe", b'{"headerId": "x"}', b"null"],
)
def test_malformed_messages_are_counted_and_change_nothing(controller, payload) -> None:
    controller.handle_message(STATE_TOPIC, payload)
    controller.handle_message("not/a/topic", b"{}")

    assert controller.counters["decode_errors"] == 1
    assert controller.counters["bad_topic"] == 1
    assert controller.fleet.by_pk(1).state is None


def test_new_vehicles_are_registered_by_the_flusher_and_trigger_dispatch(controller) -> None:
    controller.handle_message("uagv/v2/sim/AGV-9/state", state(serial="AGV-9"))

    controller.flush()
    controller.flush()

    assert [v.serial_number for v in controller.store.batches[0].new_vehicles] == ["AGV-9"]
    assert controller.fleet.vehicles[("sim", "AGV-9")].pk == 100
    assert controller.store.batches[1].snapshots[0]["pk"] == 100
    assert controller.store.dispatches >= 1


def test_a_failed_flush_is_retried_with_nothing_lost(controller) -> None:
    controller.handle_message(STATE_TOPIC, state())
    controller.sync([order()])
    controller.handle_message(STATE_TOPIC, state(header_id=2, order_id="TO-7", nodes=("b",)))
    controller.store.fail_flush = True
    controller.flush()
    controller.store.fail_flush = False

    controller.flush()

    assert [p.kind for p in controller.store.batches[-1].progress] == ["started"]
    assert controller.store.batches[-1].snapshots[0]["order_id"] == "TO-7"


def test_other_interfaces_and_own_echoes_are_ignored(controller) -> None:
    controller.handle_message("other/v2/sim/AGV-1/state", state())
    controller.handle_message("uagv/v2/sim/AGV-1/order", b"{}")
    assert controller.fleet.by_pk(1).state is None


def test_an_order_finished_in_memory_is_not_adopted_again_before_the_flush(controller) -> None:
    controller.handle_message(STATE_TOPIC, state())
    controller.sync([order()])
    controller.handle_message(
        STATE_TOPIC,
        state(
            header_id=2,
            order_id="TO-7",
            last_node="d",
            actions=(("TO-7-pick", "FINISHED"), ("TO-7-drop", "FINISHED")),
        ),
    )

    controller.sync([order()])  # the database still lists it as active
    controller.flush()

    assert [p.kind for p in controller.store.batches[-1].progress] == [
        "started",
        "step",
        "step",
        "finished",
    ]


def test_an_order_whose_route_starts_elsewhere_goes_back_to_dispatch(controller, sent) -> None:
    controller.handle_message(STATE_TOPIC, state(last_node="c"))

    controller.sync([order()])
    controller.flush()

    assert sent == []
    requeued = controller.store.batches[-1].progress[-1]
    assert requeued.kind == "requeued"
    assert "route starts at a" in requeued.detail["reason"]


def test_cancel_before_the_vehicle_took_the_order_ends_on_no_order_to_cancel(
    controller, sent
) -> None:
    controller.handle_message(STATE_TOPIC, state())
    controller.sync([order()])

    controller.sync([order(cancel_requested=True)])
    cancel = sent[-1][1]["actions"][0]
    controller.handle_message(
        STATE_TOPIC,
        state(
            header_id=2,
            actions=((cancel["actionId"], "FAILED"),),
            errors=(("noOrderToCancel", "WARNING", "x"),),
        ),
    )
    controller.flush()

    assert [p.kind for p in controller.store.batches[-1].progress] == ["cancelled"]
    assert controller.fleet.by_pk(1).execution is None
