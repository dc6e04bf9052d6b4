"""Reordered, duplicated and stale state messages: what control stores and releases.

The faults row "messages" (bench/faults/rows/messages.py) once counted 2 "regressions" of the
stored lastNodeSequenceId within one order. Its cause: a vehicle that accepts a new order still
reports the previous order's lastNodeSequenceId (with the new orderId) until it passes the new
order's first node, where the id becomes 0. Control stored that faithfully (the row's check now
allows it), but the driver read the previous order's sequence id as progress in the new order
and released its base further ahead than `base_ahead`: fixed in `OrderDriver._extend`.
"""

import json
from collections.abc import Iterator

import pytest

import vda5050
from control.controller import Controller
from control.execution import LayoutIndex
from tests.control.fakes import LINE, FakeStore, order

TOPIC = "uagv/v2/sim/AGV-1/state"
CONNECTION_TOPIC = "uagv/v2/sim/AGV-1/connection"
# The fakes' a-b-c-d line, drivable both ways (the vehicle drives back after an order).
BOTH_WAYS = LayoutIndex(
    "demo", nodes=LINE.nodes, edges=LINE.edges | {(b, a): f"{b}{a}" for a, b in LINE.edges}
)


def state(
    header_id: int,
    *,
    order_id: str = "",
    last_node: str = "a",
    last_sequence: int = 0,
    nodes: tuple[tuple[str, int, bool], ...] = (),
    timestamp: str = "2026-01-01T00:00:00.00Z",
    update_id: int = 0,
) -> bytes:
    """An encoded 2.0.0 state with explicit sequence ids: `nodes` as (id, sequenceId, released)."""
    return vda5050.encode(
        vda5050.State(
            header_id=header_id,
            timestamp=timestamp,
            version="2.0.0",
            manufacturer="sim",
            serial_number="AGV-1",
            order_id=order_id,
            order_update_id=update_id,
            last_node_id=last_node,
            last_node_sequence_id=last_sequence,
            driving=False,
            operating_mode=vda5050.OperatingMode.AUTOMATIC,
            node_states=[
                vda5050.NodeState(node_id=n, sequence_id=s, released=r) for n, s, r in nodes
            ],
            edge_states=[],
            action_states=[],
            battery_state=vda5050.BatteryState(battery_charge=80.0, charging=False),
            errors=[],
            safety_state=vda5050.SafetyState(e_stop=vda5050.EStop.NONE, field_violation=False),
            agv_position=vda5050.AgvPosition(
                x=0.0, y=0.0, theta=0.0, map_id="demo", position_initialized=True
            ),
        )
    )


def connection(header_id: int, timestamp: str = "2026-01-01T00:00:00.00Z") -> bytes:
    return vda5050.encode(
        vda5050.Connection(
            header_id=header_id,
            timestamp=timestamp,
            version="2.0.0",
            manufacturer="sim",
            serial_number="AGV-1",
            connection_state=vda5050.ConnectionState.ONLINE,
        )
    )


class Sent(list[tuple[str, dict]]):
    def __call__(self, topic: str, payload: bytes, qos: int) -> None:
        self.append((topic, json.loads(payload)))


@pytest.fixture
def sent() -> Sent:
    return Sent()


@pytest.fixture
def stepwise(sent: Sent) -> Iterator[Controller]:
    """A controller releasing one node ahead of the vehicle (the row runs with 3)."""
    ctrl = Controller(store=FakeStore(), interface_name="uagv", publish=sent, base_ahead=1)
    ctrl.load()
    ctrl.layouts = {"demo": BOTH_WAYS}
    yield ctrl
    assert ctrl.counters["handler_errors"] == 0


def orders_in(sent: Sent) -> list[dict]:
    return [message for topic, message in sent if topic.endswith("/order")]


def released(message: dict) -> list[tuple[str, int, bool]]:
    return [(n["nodeId"], n["sequenceId"], n["released"]) for n in message["nodes"]]


def stored_sequences(ctrl: Controller) -> list[tuple[str, int | None]]:
    return [
        (row["order_id"], row["last_node_sequence_id"])
        for batch in ctrl.store.batches
        for row in batch.snapshots
    ]


def test_the_previous_orders_sequence_id_is_not_progress_in_the_new_order(stepwise, sent) -> None:
    # The vehicle finished an order a→d and stands at d with lastNodeSequenceId 6.
    stepwise.handle_message(TOPIC, state(1, order_id="TO-6", last_node="d", last_sequence=6))
    stepwise.sync([order(route=["d", "c", "b", "a"])])
    first = orders_in(sent)[0]
    assert released(first) == [("d", 0, True), ("c", 2, True), ("b", 4, False), ("a", 6, False)]

    # Accepted: the new orderId, but still the old order's lastNodeSequenceId (6) until the
    # vehicle passes the new first node. 6 // 2 = route index 3 would release b and a at once.
    pending = (("d", 0, True), ("c", 2, True), ("b", 4, False), ("a", 6, False))
    stepwise.handle_message(
        TOPIC, state(2, order_id="TO-7", last_node="d", last_sequence=6, nodes=pending)
    )
    assert len(orders_in(sent)) == 1, "no update before the vehicle passed a node of TO-7"

    # It passes d (sequence 0 of TO-7): still only one node ahead of it is released.
    stepwise.handle_message(
        TOPIC, state(3, order_id="TO-7", last_node="d", last_sequence=0, nodes=pending[1:])
    )
    assert len(orders_in(sent)) == 1  # c is released already, one ahead of d
    stepwise.handle_message(
        TOPIC, state(4, order_id="TO-7", last_node="c", last_sequence=2, nodes=pending[2:])
    )
    update = orders_in(sent)[-1]
    assert update["orderUpdateId"] == 1
    assert released(update) == [("c", 2, True), ("b", 4, True), ("a", 6, False)]


def test_held_back_duplicated_and_old_stamped_states_never_move_the_stored_id_back(
    stepwise,
) -> None:
    stepwise.handle_message(TOPIC, state(1, order_id="TO-7", last_node="a", last_sequence=0))
    stepwise.flush()
    # 3 overtakes 2 (2 was held back), 4 comes twice, 5 is stamped two minutes old.
    arrivals = [
        state(3, order_id="TO-7", last_node="c", last_sequence=4),
        state(2, order_id="TO-7", last_node="b", last_sequence=2),
        state(4, order_id="TO-7", last_node="c", last_sequence=4),
        state(4, order_id="TO-7", last_node="c", last_sequence=4),
        state(5, order_id="TO-7", last_node="d", last_sequence=6, timestamp="2025-12-31T23:58:00Z"),
    ]
    for payload in arrivals:
        stepwise.handle_message(TOPIC, payload)
        stepwise.flush()

    stored = [sequence for _, sequence in stored_sequences(stepwise)]
    assert stored == sorted(stored)
    assert stored[0] == 0
    assert 2 not in stored
    assert stepwise.fleet.by_pk(1).state.last_node_sequence_id == 6
    # The old stamp is newer by header id: applied, and only shown as skew.
    assert stepwise.counters["stale"] == 1
    assert stepwise.counters["duplicate"] == 1
    assert stepwise.store.batches[-1].snapshots[-1]["last_node_sequence_id"] == 6


def test_a_redelivered_retained_online_does_not_reopen_older_header_ids(stepwise) -> None:
    """control's own reconnect to the broker re-subscribes and gets every vehicle's retained
    `connection` again: that is not a new vehicle connection, so a state held back behind a
    newer one must still be dropped."""
    stepwise.handle_message(CONNECTION_TOPIC, connection(0))
    stepwise.handle_message(TOPIC, state(7, order_id="TO-7", last_node="c", last_sequence=4))
    stepwise.handle_message(CONNECTION_TOPIC, connection(0))  # the same retained message
    stepwise.handle_message(TOPIC, state(6, order_id="TO-7", last_node="b", last_sequence=2))

    assert stepwise.fleet.by_pk(1).state.last_node_sequence_id == 4
    assert stepwise.counters["stale"] == 1


def test_a_new_online_after_a_reboot_accepts_header_ids_from_zero(stepwise) -> None:
    stepwise.handle_message(CONNECTION_TOPIC, connection(0))
    stepwise.handle_message(TOPIC, state(7, order_id="TO-7", last_node="c", last_sequence=4))
    # Rebooted: a new ONLINE (new timestamp) and header ids from 0 again.
    stepwise.handle_message(CONNECTION_TOPIC, connection(0, "2026-01-01T00:05:00.00Z"))
    stepwise.handle_message(TOPIC, state(0, order_id="", last_node="c", last_sequence=0))

    assert stepwise.fleet.by_pk(1).state.order_id == ""
    assert stepwise.counters["stale"] == 0


def test_the_fault_rows_check_tells_a_previous_orders_id_from_a_regression() -> None:
    from bench.faults.rows.messages import judge

    # Took TO-9 at S-DROP-3 with TO-5's id 26: no id of TO-9 seen yet, so not compared.
    assert judge(None, 26, of_order=False) == "leftover"
    assert judge(None, 2, of_order=True) == "progress"
    assert judge(("TO-9", 2), 4, of_order=True) == "progress"
    assert judge(("TO-9", 4), 2, of_order=True) == "regression"
    # The previous order's id again after TO-9 made progress: a stale state got through.
    assert judge(("TO-9", 2), 26, of_order=False) == "regression"
