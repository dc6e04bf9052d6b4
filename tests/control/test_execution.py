import msgspec
import pytest

import vda5050
from control.execution import OrderExecution, Phase, Window
from control.order_messages import (
    LoadJob,
    OrderLimits,
    build_order,
    extension_window,
    initial_window,
)
from control.traffic_support import window as traffic_window
from tests.control.fakes import LINE
from tests.vda5050.support import validator

JOB = LoadJob(load_id="L1", load_type="EPAL", pick_station="PICK-1", drop_station="DROP-1")


def planned() -> OrderExecution:
    return OrderExecution.plan(
        transport_order_id=7, vda_order_id="TO-7", route=["a", "b", "c", "d"], pickup="b"
    )


@pytest.mark.parametrize("version", ["2.0.0", "2.1.0"])
def test_built_order_validates_against_the_official_schema(version: str) -> None:
    nodes, edges = build_order(planned(), LINE, Window(0, 3, 1), JOB)
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
    nodes, edges = build_order(execution, LINE, Window(0, 3, 3), JOB)

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


def test_base_then_horizon_with_edges_released_only_between_released_nodes() -> None:
    nodes, edges = build_order(planned(), LINE, Window(0, 3, 1), JOB)

    assert [n.released for n in nodes] == [True, True, False, False]
    assert [e.released for e in edges] == [True, False, False]


def test_an_update_starts_at_the_stitching_node_with_its_sequence_id_and_actions() -> None:
    execution = planned()
    first, _ = build_order(execution, LINE, Window(0, 3, 1), JOB)

    nodes, edges = build_order(execution, LINE, Window(1, 3, 2), JOB)

    assert nodes[0] == first[1]  # same node id, sequence id 2, released, same pick action
    assert [n.sequence_id for n in nodes] == [2, 4, 6]
    assert [e.sequence_id for e in edges] == [3, 5]
    assert [n.released for n in nodes] == [True, True, False]


@pytest.mark.parametrize(
    ("limits", "expected"),
    [
        (OrderLimits(), Window(0, 9, 9)),
        (OrderLimits(base_ahead=2), Window(0, 9, 2)),
        (OrderLimits(max_nodes=4), Window(0, 3, 3)),
        (OrderLimits(max_nodes=4, base_ahead=1), Window(0, 3, 1)),
        (OrderLimits(base_ahead=2, horizon=3), Window(0, 5, 2)),
        (OrderLimits(base_ahead=2, horizon=0), Window(0, 2, 2)),
        (OrderLimits(max_nodes=4, base_ahead=1, horizon=5), Window(0, 3, 1)),
    ],
)
def test_initial_window_respects_base_ahead_and_the_message_size_limit(limits, expected) -> None:
    assert initial_window(10, limits) == expected


def test_extension_follows_the_vehicle_and_stops_when_all_is_released() -> None:
    limits = OrderLimits(max_nodes=4, base_ahead=2)

    assert extension_window(10, released_until=2, passed=1, limits=limits) == Window(2, 5, 3)
    assert extension_window(10, released_until=3, passed=1, limits=limits) is None
    assert extension_window(10, released_until=8, passed=8, limits=limits) == Window(8, 9, 9)


def test_the_horizon_moves_on_with_the_base_and_ends_with_the_route() -> None:
    limits = OrderLimits(base_ahead=2, horizon=2)

    assert extension_window(10, released_until=2, passed=1, limits=limits) == Window(2, 5, 3)
    assert extension_window(10, released_until=3, passed=5, limits=limits) == Window(3, 9, 7)
    assert extension_window(10, released_until=7, passed=8, limits=limits) == Window(7, 9, 9)


def test_traffic_windows_carry_the_horizon_limit_after_the_released_base() -> None:
    assert traffic_window(10, 0, 3, None, horizon=2) == Window(0, 5, 3)
    assert traffic_window(10, 3, 8, None, horizon=2) == Window(3, 9, 8)
    assert traffic_window(10, 0, 3, 4, horizon=2) == Window(0, 3, 3)  # message size first
