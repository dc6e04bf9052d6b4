"""Multi-stop orders in `control`: one VDA 5050 order with every stop's action, step progress
reported per stop, and the store reading the stops of an assigned order."""

import msgspec
import pytest

import vda5050
from control.execution import OrderExecution, Progress, StepPlan, Window
from control.order_messages import LoadJob, build_order
from control.persistence import DjangoStore, _apply
from maps.models import Station
from orders import services
from orders.models import OrderEvent, OrderStep, TransportOrder
from orders.services import StepSpec
from tests.control.fakes import LINE, state
from tests.factories import VehicleFactory
from tests.vda5050.support import validator

JOB = LoadJob(load_id="L1", load_type="EPAL", pick_station="", drop_station="")
STOPS = (
    StepPlan(1, "pick", "PICK-1"),
    StepPlan(2, "detectObject", "CHECK", {"objectType": "pallet"}),
    StepPlan(2, "pick", "PICK-2"),
    StepPlan(3, "drop", "DROP-1", {"lhd": "forks"}),
)


def planned() -> OrderExecution:
    return OrderExecution.plan(
        transport_order_id=7, vda_order_id="TO-7", route=["a", "b", "c", "d"], steps=STOPS
    )


def test_every_stop_is_a_node_action_at_its_node_in_step_order() -> None:
    nodes, _ = build_order(planned(), LINE, Window(0, 3, 3), JOB)

    actions = [[(a.action_type, a.action_id) for a in n.actions] for n in nodes]
    assert actions == [
        [],
        [("pick", "TO-7-1-pick")],
        [("detectObject", "TO-7-detectObject"), ("pick", "TO-7-3-pick")],
        [("drop", "TO-7-drop")],
    ]
    drop = {p.key: p.value for p in nodes[3].actions[0].action_parameters}
    assert drop == {
        "stationType": "floor",
        "stationName": "DROP-1",
        "loadType": "EPAL",
        "loadId": "L1",
        "lhd": "forks",
    }
    custom = nodes[2].actions[0].action_parameters
    assert [(p.key, p.value) for p in custom] == [("objectType", "pallet")]


@pytest.mark.parametrize("version", ["2.0.0", "2.1.0"])
def test_a_multi_stop_order_validates_against_the_official_schema(version: str) -> None:
    nodes, edges = build_order(planned(), LINE, Window(0, 3, 3), JOB)
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

    document = msgspec.json.decode(vda5050.encode(message))
    assert list(validator(version, "order").iter_errors(document)) == []


def observe(execution: OrderExecution, **kwargs: object) -> list[Progress]:
    return execution.observe(vda5050.decode(vda5050.TopicKind.STATE, state(**kwargs)))


def test_each_stop_reports_its_step_number_once_and_the_order_ends_after_the_last() -> None:
    execution = planned()
    execution.released_until = execution.update_id = 3  # all sent and confirmed
    ids = [s.action_id for s in execution.steps]

    first = observe(
        execution,
        order_id="TO-7",
        update_id=3,
        last_node="c",
        nodes=("d",),
        actions=(
            (ids[0], "FINISHED"),
            (ids[1], "FINISHED"),
            (ids[2], "RUNNING"),
            (ids[3], "WAITING"),
        ),
    )
    again = observe(
        execution,
        order_id="TO-7",
        update_id=3,
        last_node="c",
        nodes=("d",),
        actions=(
            (ids[0], "FINISHED"),
            (ids[1], "FINISHED"),
            (ids[2], "RUNNING"),
            (ids[3], "WAITING"),
        ),
    )
    last = observe(
        execution,
        order_id="TO-7",
        update_id=3,
        last_node="d",
        actions=tuple((i, "FINISHED") for i in ids),
    )

    assert [(p.kind, p.detail) for p in first] == [
        ("started", {}),
        ("step", {"step": "pick", "node": "b", "index": "0"}),
        ("step", {"step": "detectObject", "node": "c", "index": "1"}),
    ]
    assert again == []
    assert [(p.kind, p.detail.get("index")) for p in last] == [
        ("step", "2"),
        ("step", "3"),
        ("finished", None),
    ]


def test_a_failed_custom_action_fails_the_order() -> None:
    execution = planned()
    events = observe(
        execution,
        order_id="TO-7",
        last_node="c",
        nodes=("d",),
        actions=(("TO-7-detectObject", "FAILED"),),
    )

    assert events[-1].kind == "failed"
    assert events[-1].detail["reason"].startswith("detectObject action failed")


@pytest.mark.django_db(transaction=True)  # the store closes stale connections
def test_the_store_hands_control_the_stops_and_applies_their_progress(demo_map) -> None:
    VehicleFactory(last_node_id="A0.0")
    spec = [
        StepSpec(Station.objects.get(station_id=s), o, a)
        for s, o, a in (
            ("PICK-1", "PICK", ""),
            ("PICK-3", "ACTION", "detectObject"),
            ("DROP-2", "DROP", ""),
        )
    ]
    order = services.create_transport_order(steps=spec)
    services.dispatch_pending_orders()
    order.refresh_from_db()

    (active,) = [o for o in DjangoStore().active_orders() if o.transport_order_id == order.pk]
    _apply(Progress("step", order.pk, {"step": "detectObject", "node": "S-PICK-3", "index": "1"}))

    assert [(s.index, s.action_type, s.station) for s in active.steps] == [
        (order.route_steps[0], "pick", "PICK-1"),
        (order.route_steps[1], "detectObject", "PICK-3"),
        (order.route_steps[2], "drop", "DROP-2"),
    ]
    assert OrderStep.objects.get(order=order, index=1).finished_at is not None
    assert order.events.filter(kind=OrderEvent.Kind.STEP_REACHED).get().detail["index"] == 1
    assert TransportOrder.objects.get(pk=order.pk).status == TransportOrder.Status.ASSIGNED
