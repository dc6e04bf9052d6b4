import msgspec
import pytest

import vda5050
from control.execution import OrderExecution, Phase, build_order
from tests.control.fakes import LINE
from tests.vda5050.support import validator


def planned() -> OrderExecution:
    return OrderExecution.plan(
        transport_order_id=7, vda_order_id="TO-7", route=["a", "b", "c", "d"], pickup="b"
    )


@pytest.mark.parametrize("version", ["2.0.0", "2.1.0"])
def test_built_order_validates_against_the_official_schema(version: str) -> None:
    nodes, edges = build_order(
        planned(),
        LINE,
        load_id="L1",
        load_type="EPAL",
        pick_station="PICK-1",
        drop_station="DROP-1",
    )
    message = vda5050.Order(
        header_id=0,
        timestamp=vda5050.now_timestamp(version),
        version=version,
        manufacturer="sim",
        serial_number="AGV-1",
        order_id="TO-7",
        order_update_id=0,
        nodes=nodes,
        edges=edges,
    )

    errors = list(
        validator(version, "order").iter_errors(msgspec.json.decode(vda5050.encode(message)))
    )

    assert errors == []


def test_sequence_ids_and_actions_follow_the_route() -> None:
    execution = planned()
    nodes, edges = build_order(
        execution, LINE, load_id="", load_type="EPAL", pick_station="PICK-1", drop_station="DROP-1"
    )

    assert [n.sequence_id for n in nodes] == [0, 2, 4, 6]
    assert [e.sequence_id for e in edges] == [1, 3, 5]
    assert [(e.start_node_id, e.end_node_id) for e in edges] == [("a", "b"), ("b", "c"), ("c", "d")]
    assert all(n.released for n in nodes)
    assert all(e.released for e in edges)
    assert [[a.action_type for a in n.actions] for n in nodes] == [[], ["pick"], [], ["drop"]]
    assert nodes[1].actions[0].action_id == execution.pick_action_id


def test_action_ids_are_stable_so_a_restarted_control_can_adopt_the_order() -> None:
    assert planned().pick_action_id == planned().pick_action_id


def test_failed_pick_ends_the_order() -> None:
    execution = planned()
    state = vda5050.decode(
        vda5050.TopicKind.STATE,
        _state_bytes(
            order_id="TO-7", actions=((execution.pick_action_id, "FAILED"),), nodes=("c",)
        ),
    )

    events = execution.observe(state)

    assert [e.kind for e in events] == ["started", "failed"]
    assert execution.phase is Phase.DONE


def _state_bytes(**kwargs: object) -> bytes:
    from tests.control.fakes import state

    return state(**kwargs)  # type: ignore[arg-type]
