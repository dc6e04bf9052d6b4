"""A vehicle that took an order and then reports none (it rebooted mid-order) ends that order
as failed with the reason; before, the order stayed IN_PROGRESS forever (found by the link
row of bench/faults: 2 of 18 orders never ended after vehicle processes were SIGKILLed)."""

import vda5050
from control.execution import OrderExecution, Phase
from tests.control.fakes import state


def running() -> OrderExecution:
    execution = OrderExecution.plan(
        transport_order_id=7, vda_order_id="TO-7", route=["a", "b", "c", "d"], pickup="b"
    )
    accepted = vda5050.decode(
        vda5050.TopicKind.STATE, state(order_id="TO-7", nodes=("b", "c", "d"))
    )
    assert [e.kind for e in execution.observe(accepted)] == ["started"]
    return execution


def test_a_running_order_the_vehicle_no_longer_lists_fails_with_the_reason() -> None:
    execution = running()
    rebooted = vda5050.decode(vda5050.TopicKind.STATE, state(header_id=2, order_id=""))

    events = execution.observe(rebooted)

    assert [(e.kind, e.detail) for e in events] == [
        ("failed", {"reason": "vehicle no longer has the order (reports 'none')"})
    ]
    assert execution.phase is Phase.DONE


def test_a_sent_order_not_yet_taken_keeps_waiting_for_the_vehicle() -> None:
    execution = OrderExecution.plan(
        transport_order_id=7, vda_order_id="TO-7", route=["a", "b", "c", "d"], pickup="b"
    )
    still_idle = vda5050.decode(vda5050.TopicKind.STATE, state(order_id=""))

    assert execution.observe(still_idle) == []
    assert execution.phase is Phase.SENT
