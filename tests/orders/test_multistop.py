"""Multi-stop transport orders: API, checks, dispatch through every stop, step progress."""

import pytest

from fleet.exceptions import InvalidRequestError
from maps.models import NodeProperty, Station, VehicleType
from maps.services import mark_layout_changed
from orders import services
from orders.models import OrderEvent, OrderStep, TransportOrder
from orders.services import StepSpec
from tests.factories import VehicleFactory

THREE_STOPS = {
    "steps": [
        {"station": "PICK-1", "operation": "PICK"},
        {
            "station": "PICK-3",
            "operation": "action",
            "action_type": "detectObject",
            "parameters": {"objectType": "pallet"},
        },
        {"station": "DROP-2", "operation": "DROP", "parameters": {"lhd": "forks"}},
    ],
    "load_id": "PAL-9",
    "metadata": {"wave": 12},
}


def test_api_creates_a_multi_stop_order_and_shows_its_steps(api, demo_map) -> None:
    response = api.post("/api/v1/orders/", THREE_STOPS, format="json")

    body = response.json()
    assert response.status_code == 201, body
    assert [(s["index"], s["station"], s["operation"]) for s in body["steps"]] == [
        (0, "PICK-1", "PICK"),
        (1, "PICK-3", "ACTION"),
        (2, "DROP-2", "DROP"),
    ]
    assert body["steps"][1]["action_type"] == "detectObject"
    assert body["steps"][1]["parameters"] == {"objectType": "pallet"}
    assert (body["source"], body["destination"], body["metadata"]) == (
        "PICK-1",
        "DROP-2",
        {"wave": 12},
    )
    assert api.get(f"/api/v1/orders/{body['id']}/").json()["steps"] == body["steps"]
    assert api.get("/api/v1/orders/").json()["results"][0]["steps"] == body["steps"]


def test_a_pick_drop_order_is_a_two_step_order(api, demo_map) -> None:
    body = api.post(
        "/api/v1/orders/", {"source": "PICK-1", "destination": "DROP-3"}, format="json"
    ).json()

    assert [(s["station"], s["operation"]) for s in body["steps"]] == [
        ("PICK-1", "PICK"),
        ("DROP-3", "DROP"),
    ]


@pytest.mark.parametrize(
    ("change", "field"),
    [
        ({"steps": [{"station": "NOPE", "operation": "PICK"}]}, "steps[0].station"),
        ({"steps": [{"station": "PICK-1", "operation": "FLY"}]}, "steps"),
        ({"steps": []}, "steps"),
        ({"source": "PICK-1"}, "steps"),
        ({"intended_vehicle": "NO-SUCH-AGV"}, "intended_vehicle"),
        ({"vehicle_type": "no.such.type"}, "vehicle_type"),
        ({"metadata": [1, 2]}, "metadata"),
    ],
)
def test_bad_steps_get_400_naming_the_field(api, demo_map, change, field) -> None:
    response = api.post("/api/v1/orders/", {**THREE_STOPS, **change}, format="json")

    assert response.status_code == 400
    assert field in response.json(), response.json()
    assert not TransportOrder.objects.exists()


@pytest.mark.parametrize(
    ("step", "reason"),
    [
        ({"station": "PICK-2", "operation": "ACTION"}, "step 2 (PICK-2): a custom action needs"),
        (
            {"station": "PICK-2", "operation": "PICK", "action_type": "x"},
            "action_type is only for operation ACTION",
        ),
        (
            {"station": "PICK-2", "operation": "PICK", "parameters": {"stationName": "x"}},
            "stationName are set by the system",
        ),
    ],
)
def test_steps_that_cannot_be_done_get_422_with_the_reason(api, demo_map, step, reason) -> None:
    body = {"steps": [{"station": "PICK-1", "operation": "PICK"}, step]}

    response = api.post("/api/v1/orders/", body, format="json")

    assert response.status_code == 422
    assert reason in response.json()["detail"]
    assert not TransportOrder.objects.exists()


def only_for(vehicle_type: VehicleType, station: Station) -> None:
    """Make the station's node usable by `vehicle_type` alone."""
    NodeProperty.objects.create(node=station.node, vehicle_type=vehicle_type)
    mark_layout_changed(maps=[station.map])


def test_a_step_the_vehicle_type_cannot_reach_is_refused(api, demo_map) -> None:
    small = VehicleType.objects.create(type_id="sim.Small")
    VehicleType.objects.create(type_id="sim.Big")
    only_for(small, Station.objects.get(station_id="PICK-3"))

    refused = api.post("/api/v1/orders/", {**THREE_STOPS, "vehicle_type": "sim.Big"}, format="json")
    accepted = api.post(
        "/api/v1/orders/", {**THREE_STOPS, "vehicle_type": "sim.Small"}, format="json"
    )

    assert refused.status_code == 422
    assert refused.json()["detail"] == (
        "step 2 (PICK-3) cannot be reached from step 1 (PICK-1) for vehicle type sim.Big"
    )
    assert accepted.status_code == 201
    assert accepted.json()["vehicle_type"] == "sim.Small"


def steps(demo_map, *spec: tuple[str, str]) -> list[StepSpec]:
    return [
        StepSpec(
            station=Station.objects.get(map=demo_map, station_id=station_id),
            operation="ACTION" if operation not in ("PICK", "DROP") else operation,
            action_type=operation if operation not in ("PICK", "DROP") else "",
        )
        for station_id, operation in spec
    ]


def test_dispatch_routes_through_every_step_and_records_where_each_is(demo_map) -> None:
    VehicleFactory(last_node_id="A0.0")
    order = services.create_transport_order(
        steps=steps(demo_map, ("PICK-1", "PICK"), ("PICK-4", "detectObject"), ("DROP-2", "DROP"))
    )

    services.dispatch_pending_orders()

    order.refresh_from_db()
    assert order.status == TransportOrder.Status.ASSIGNED
    assert [order.route[i] for i in order.route_steps] == ["S-PICK-1", "S-PICK-4", "S-DROP-2"]
    assert order.route_steps == sorted(order.route_steps)
    assert order.route_steps[-1] == len(order.route) - 1


def test_dispatch_keeps_to_the_intended_vehicle_and_vehicle_type(demo_map) -> None:
    big = VehicleType.objects.create(type_id="sim.Big", series_name="Big")
    near = VehicleFactory(last_node_id="A1.3")
    far = VehicleFactory(last_node_id="A5.0")
    typed = VehicleFactory(
        last_node_id="A5.3", factsheet={"typeSpecification": {"seriesName": "Big"}}
    )
    pick_drop = steps(demo_map, ("PICK-1", "PICK"), ("DROP-1", "DROP"))
    intended = services.create_transport_order(steps=pick_drop, intended_vehicle=far)
    of_type = services.create_transport_order(steps=pick_drop, vehicle_type=big)

    services.dispatch_pending_orders()

    intended.refresh_from_db()
    of_type.refresh_from_db()
    assert (intended.vehicle, of_type.vehicle) == (far, typed)
    near.refresh_from_db()
    assert not near.transport_orders.exists()


def test_orders_say_which_restriction_keeps_them_waiting(demo_map) -> None:
    VehicleType.objects.create(type_id="sim.Big")
    busy = VehicleFactory(
        last_node_id="A0.0",
        factsheet={"loadSpecification": {"loadSets": [{"setName": "pallets", "loadType": "EPAL"}]}},
    )
    other = VehicleFactory(last_node_id="A1.0")
    pick_drop = steps(demo_map, ("PICK-1", "PICK"), ("DROP-1", "DROP"))
    TransportOrder.objects.create(
        source=pick_drop[0].station,
        destination=pick_drop[1].station,
        vehicle=other,
        status=TransportOrder.Status.ASSIGNED,
    )
    waits_for_other = services.create_transport_order(steps=pick_drop, intended_vehicle=other)
    waits_for_type = services.create_transport_order(
        steps=pick_drop, vehicle_type=VehicleType.objects.get()
    )
    odd_load = services.create_transport_order(steps=pick_drop, load_type="GITTERBOX")
    # The idle vehicle has no factsheet action list, but declares only EPAL loads.

    services.dispatch_pending_orders()

    notes = {
        o.pk: o.dispatch_note
        for o in TransportOrder.objects.filter(
            pk__in=[waits_for_other.pk, waits_for_type.pk, odd_load.pk]
        )
    }
    assert notes == {
        waits_for_other.pk: f"waits for its intended vehicle {other} to be free",
        waits_for_type.pk: "no idle vehicle of type sim.Big",
        odd_load.pk: "no idle vehicle can handle load type GITTERBOX",
    }
    assert not busy.transport_orders.exists()


def test_a_vehicle_without_the_step_action_is_not_chosen(demo_map) -> None:
    declares = [{"actionType": t, "actionScopes": ["NODE"]} for t in ("pick", "drop")]
    VehicleFactory(last_node_id="A0.0", factsheet={"protocolFeatures": {"agvActions": declares}})
    order = services.create_transport_order(
        steps=steps(demo_map, ("PICK-1", "PICK"), ("PICK-2", "detectObject"), ("DROP-1", "DROP"))
    )

    services.dispatch_pending_orders()

    order.refresh_from_db()
    assert order.status == TransportOrder.Status.NEW
    assert order.dispatch_note == "no idle vehicle can handle action detectObject"


def test_steps_must_be_on_one_map_and_need_a_custom_action_type(demo_map) -> None:
    with pytest.raises(InvalidRequestError, match="a custom action needs an action_type"):
        services.create_transport_order(
            steps=[StepSpec(Station.objects.get(station_id="PICK-1"), "ACTION")]
        )
    with pytest.raises(InvalidRequestError, match="not both"):
        services.create_transport_order(
            source=Station.objects.get(station_id="PICK-1"),
            steps=steps(demo_map, ("PICK-1", "PICK")),
        )
    assert not TransportOrder.objects.exists()


def test_each_step_is_recorded_once_when_the_vehicle_finishes_it(demo_map) -> None:
    order = services.create_transport_order(
        steps=steps(demo_map, ("PICK-1", "PICK"), ("PICK-2", "PICK"), ("DROP-1", "DROP"))
    )

    services.mark_step_reached(order_id=order.pk, step="pick", node_id="S-PICK-2", index=1)
    services.mark_step_reached(order_id=order.pk, step="pick", node_id="S-PICK-2", index=1)
    services.mark_step_reached(order_id=order.pk, step="pick", node_id="S-PICK-1")  # old control

    done = dict(OrderStep.objects.filter(order=order).values_list("index", "finished_at"))
    assert None not in (done[0], done[1])
    assert done[2] is None
    details = [
        e.detail for e in order.events.filter(kind=OrderEvent.Kind.STEP_REACHED).order_by("pk")
    ]
    assert details == [
        {"step": "pick", "node": "S-PICK-2", "index": 1},
        {"step": "pick", "node": "S-PICK-1", "index": 0},
    ]
