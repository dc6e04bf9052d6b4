"""Master-control rules in every version (2.0.0, 2.1.0, 3.0.0): instant actions that conflict
with the order (E.23), the factsheet's string limits (J.44) and order updates after the vehicle
finished its base (B.13). Every published message is validated against its schema."""

# The fixtures (and the per-version parametrisation) are those of test_controller.py.
# ruff: noqa: F811

import re

import msgspec
import pytest

import vda5050
from control.capabilities import Capabilities, StringLimits
from simulator import wire
from simulator.vehicle import StartPose, VehicleConfig, VirtualVehicle
from tests.control import fakes
from tests.control.fakes import order, state
from tests.control.test_controller import (  # noqa: F401 - fixtures
    controller,
    instant_actions_in,
    orders_in,
    protocol_version,
    released,
    sent,
    stepwise,
)
from vda5050.enums import ActionScope, ValueDataType

_PARAMS = {
    "initPosition": ("x", "y", "theta", "mapId", "lastNodeId"),
    "enableMap": ("mapId", "mapVersion"),
    "startCharging": (),
    "pick": (),
    "stopCharging": (),
    "retry": ("actionId",),
}


def declaring(*action_types: str, strings: StringLimits | None = None) -> Capabilities:
    """A factsheet that declares `action_types` as instant actions (parameters as needed)."""
    actions = {
        t: vda5050.AgvAction(
            action_type=t,
            action_scopes=[ActionScope.INSTANT, ActionScope.NODE],
            action_parameters=[
                vda5050.ActionParameterSpec(key=k, value_data_type=ValueDataType.STRING)
                for k in _PARAMS.get(t, ())
            ],
        )
        for t in action_types
    }
    return Capabilities(actions, strings=strings or StringLimits())


INIT = {"x": 0.0, "y": 0.0, "theta": 0.0, "mapId": "demo", "lastNodeId": "a"}


def command(controller, action_type: str, parameters: dict, request: str) -> None:
    controller.execute(
        {
            "kind": "vehicle.instant_action",
            "vehicle": 1,
            "action_type": action_type,
            "parameters": parameters,
            "request": request,
        }
    )


def outcome(controller, request: str) -> tuple[str, str]:
    tracks = controller.fleet.by_pk(1).instant_actions.values()
    (result,) = [t for t in tracks if t.request == request]
    return result.status, result.reason


@pytest.mark.parametrize(
    ("action_type", "parameters", "reason"),
    [
        ("initPosition", INIT, "initPosition relocates the vehicle; not while order TO-7 is"),
        ("startCharging", {}, "startCharging keeps the vehicle at the charger; not while order"),
        ("pick", {}, "pick would run beside order TO-7; send it as part of an order"),
        ("enableMap", {"mapId": "demo", "mapVersion": "2"}, "enableMap of map demo while order"),
        ("cancelOrder", {}, "order TO-7 is driven by control: cancel its transport order"),
    ],
)
def test_E23_instant_actions_that_conflict_with_the_running_order_are_refused(
    controller, sent, action_type, parameters, reason
) -> None:
    controller.handle_message(fakes.topic(), state(header_id=1))
    controller.fleet.by_pk(1).capabilities = declaring(*_PARAMS)
    controller.sync([order()])
    controller.handle_message(
        fakes.topic(), state(header_id=2, order_id="TO-7", nodes=("b", "c", "d"), driving=True)
    )
    before = len(sent)

    command(controller, action_type, parameters, "c-1")
    controller.flush()

    status, why = outcome(controller, "c-1")
    assert (status, why[: len(reason)]) == ("REFUSED", reason)
    recorded = [o for b in controller.store.batches for o in b.command_outcomes]
    assert [(o.request, o.status) for o in recorded] == [("c-1", "REFUSED")]
    assert len(sent) == before


def test_E23_the_same_actions_go_out_when_nothing_conflicts(controller, sent) -> None:
    controller.handle_message(fakes.topic(), state(header_id=1))
    controller.fleet.by_pk(1).capabilities = declaring(*_PARAMS)

    command(controller, "initPosition", INIT, "c-1")
    command(controller, "startCharging", {}, "c-2")
    command(controller, "stopCharging", {}, "c-3")

    assert [outcome(controller, r)[0] for r in ("c-1", "c-2", "c-3")] == ["SENT"] * 3
    v3 = fakes.PROTOCOL["version"].startswith("3.")
    expected = "initializePosition" if v3 else "initPosition"
    assert instant_actions_in(sent)[-3:] == [expected, "startCharging", "stopCharging"]


def test_E23_relocating_a_driving_vehicle_is_refused_even_without_an_order(controller) -> None:
    controller.handle_message(fakes.topic(), state(header_id=1, driving=True))
    controller.fleet.by_pk(1).capabilities = declaring("initPosition")

    command(controller, "initPosition", INIT, "c-1")

    assert outcome(controller, "c-1") == (
        "REFUSED",
        "initPosition relocates the vehicle; not while the vehicle is driving",
    )


def test_E23_retry_names_a_retriable_action(controller) -> None:
    controller.handle_message(fakes.topic(), state(header_id=1))
    controller.fleet.by_pk(1).capabilities = declaring("retry")
    command(controller, "retry", {"actionId": "nothing"}, "c-1")
    assert outcome(controller, "c-1") == ("REFUSED", "action nothing is not RETRIABLE")


@pytest.mark.parametrize(
    ("limits", "reason"),
    [
        (StringLimits(id_len=3), "not sent: orderId 'TO-7' exceeds idLen 3"),
        (StringLimits(id_numerical_only=True), "not sent: orderId 'TO-7' is not numerical"),
        (StringLimits(msg_len=200), "not sent: message of "),
        (StringLimits(load_id_len=4), "not sent: loadId 'LOAD-12345' exceeds loadIdLen 4"),
        (StringLimits(topic_serial_len=4), "not sent: serial number 'AGV-1' exceeds"),
        (StringLimits(topic_elem_len=3), "not sent: topic level 'uagv' exceeds"),
        (StringLimits(enum_len=3), "not sent: blockingType 'HARD' exceeds enumLen 3"),
    ],
)
def test_J44_an_order_that_breaks_a_string_limit_is_refused_not_sent(
    controller, sent, limits, reason
) -> None:
    controller.handle_message(fakes.topic(), state(header_id=1))
    controller.fleet.by_pk(1).capabilities = declaring(strings=limits)

    controller.sync([order(load_id="LOAD-12345")])
    controller.sync([order(load_id="LOAD-12345")])  # not tried again
    controller.flush()

    assert orders_in(sent) == []
    (failed,) = [p for b in controller.store.batches for p in b.progress]
    assert failed.kind == "failed"
    assert failed.detail["reason"].startswith(reason)
    assert controller.counters["limit_refused"] == 1
    assert controller.fleet.by_pk(1).execution is None


def test_J44_only_limits_on_ids_enums_and_load_ids_make_messages_walked() -> None:
    assert not StringLimits().limits_strings
    assert not StringLimits(msg_len=100, topic_serial_len=8, topic_elem_len=8).limits_strings
    for limits in (
        StringLimits(id_len=3),
        StringLimits(id_numerical_only=True),
        StringLimits(enum_len=3),
        StringLimits(load_id_len=4),
    ):
        assert limits.limits_strings


def test_J44_a_refused_message_leaves_no_header_id_gap(controller, sent) -> None:
    controller.handle_message(fakes.topic(), state(header_id=1))
    vehicle = controller.fleet.by_pk(1)
    vehicle.capabilities = declaring(strings=StringLimits(id_len=3))
    controller.sync([order()])
    vehicle.capabilities = declaring()
    controller.driver._ended.clear()  # a new assignment of the same order

    controller.sync([order()])

    (message,) = orders_in(sent)
    assert message["headerId"] == 0


def test_J44_an_instant_action_that_breaks_a_limit_is_refused(controller, sent) -> None:
    controller.handle_message(fakes.topic(), state(header_id=1))
    controller.fleet.by_pk(1).capabilities = declaring(strings=StringLimits(msg_len=100))
    before = len(sent)

    controller.execute({"kind": "vehicle.pause", "vehicle": 1, "request": "p"})

    status, reason = outcome(controller, "p")
    assert status == "REFUSED"
    assert reason.startswith("message of ")
    assert reason.endswith("exceeds the vehicle's msgLen 100")
    assert len(sent) == before


@pytest.mark.parametrize(
    ("limits", "pattern"),
    [(StringLimits(id_len=8), r"[0-9a-f]{8}"), (StringLimits(id_numerical_only=True), r"[0-9]+")],
)
def test_J44_our_action_ids_fit_the_vehicle_id_limits(controller, sent, limits, pattern) -> None:
    controller.handle_message(fakes.topic(), state(header_id=1))
    controller.fleet.by_pk(1).capabilities = declaring(strings=limits)

    controller.execute({"kind": "vehicle.pause", "vehicle": 1, "request": "p"})

    assert outcome(controller, "p")[0] == "SENT"
    action_id = sent[-1][1]["actions"][0]["actionId"]
    assert re.fullmatch(pattern, action_id)


def test_B13_an_update_after_the_vehicle_finished_its_base_starts_at_its_last_node(
    stepwise, sent
) -> None:
    stepwise.driver.base_ahead = None
    stepwise.handle_message(fakes.topic(), state(header_id=1))
    stepwise.fleet.by_pk(1).capabilities = Capabilities({}, max_order_nodes=2)
    stepwise.sync([order()])
    # The vehicle drove the whole base (a, b; no horizon) and has nothing left: finished.
    stepwise.handle_message(
        fakes.topic(),
        state(header_id=2, order_id="TO-7", last_node="b", actions=(("TO-7-pick", "FINISHED"),)),
    )
    stepwise.flush()

    first, update = orders_in(sent)
    assert released(first) == [("a", 0, True), ("b", 2, True)]
    assert update["orderUpdateId"] == 1
    # B.13: first node == lastNodeId and lastNodeSequenceId of the finished order.
    assert released(update)[0] == ("b", 2, True)
    kinds = [p.kind for b in stepwise.store.batches for p in b.progress]
    assert "finished" not in kinds  # G.35: the route is not done


def test_B13_a_finished_order_is_updated_to_its_end_and_then_finishes(stepwise, sent) -> None:
    stepwise.driver.base_ahead = None
    stepwise.handle_message(fakes.topic(), state(header_id=1))
    stepwise.fleet.by_pk(1).capabilities = Capabilities({}, max_order_nodes=3)
    stepwise.sync([order()])
    pick = (("TO-7-pick", "FINISHED"),)
    stepwise.handle_message(
        fakes.topic(), state(header_id=2, order_id="TO-7", last_node="c", actions=pick)
    )
    stepwise.handle_message(
        fakes.topic(),
        state(
            header_id=3,
            order_id="TO-7",
            update_id=1,
            last_node="d",
            actions=(*pick, ("TO-7-drop", "FINISHED")),
        ),
    )
    stepwise.flush()

    first, update = orders_in(sent)
    assert released(update) == [("c", 4, True), ("d", 6, True)]
    assert stepwise.store.batches[-1].progress[-1].kind == "finished"


def test_J44_the_string_limits_come_from_the_vehicle_factsheet(controller, sent) -> None:
    vehicle = VirtualVehicle(
        VehicleConfig(version=fakes.PROTOCOL["version"]), StartPose("demo", "a", 0.0, 0.0)
    )
    factsheet = msgspec.json.decode(vda5050.encode(wire.factsheet(vehicle)))
    limits = factsheet["protocolLimits"]
    if fakes.PROTOCOL["version"].startswith("3."):
        limits["maximumStringLengths"]["maximumIdLength"] = 3
    else:
        limits["maxStringLens"]["idLen"] = 3
    controller.handle_message(fakes.topic(), state(header_id=1))
    controller.handle_message(fakes.topic(kind="factsheet"), msgspec.json.encode(factsheet))

    controller.sync([order()])
    controller.flush()

    assert orders_in(sent) == []
    failed = controller.store.batches[-1].progress[-1]
    assert failed.detail["reason"] == "not sent: orderId 'TO-7' exceeds idLen 3"
