"""Loads and vehicles (REFERENCE J.42, J.46): the heaviest load a factsheet allows, and legs
with a load on board routed under the layout's load restrictions."""

from types import SimpleNamespace

from inventory.models import LoadCarrier
from orders import capability, services
from orders.models import OrderStep, TransportOrder
from orders.services.fit import route_through_steps
from tests.factories import VehicleFactory
from traffic import RoutingGraph, VehicleProfile
from traffic.costs import EdgeRule
from traffic.elements import GraphEdge, GraphNode

FACTSHEET = {
    "typeSpecification": {"maxLoadMass": 1000},
    "loadSpecification": {
        "loadSets": [
            {"setName": "light", "loadType": "KLT", "maxWeight": 50},
            {"setName": "pallet", "loadType": "EPAL"},
        ]
    },
}


def test_the_load_limit_is_the_type_maximum_lowered_by_the_load_set() -> None:
    assert capability.max_load_mass(FACTSHEET, "EPAL") == 1000
    assert capability.max_load_mass(FACTSHEET, "KLT") == 50
    assert capability.max_load_mass({}, "EPAL") is None
    refusal = capability.refusal(FACTSHEET, load_type="KLT", actions=[], load_weight=60)
    assert refusal == "a load of 60 kg (at most 50 kg)"
    assert capability.refusal(FACTSHEET, load_type="EPAL", actions=[], load_weight=900) is None
    assert capability.refusal(FACTSHEET, load_type="EPAL", actions=[], load_weight=None) is None


def test_dispatch_gives_a_heavy_load_only_to_a_vehicle_that_can_carry_it(station) -> None:
    def vehicle(node: str, max_mass: float) -> object:
        return VehicleFactory(
            last_node_id=node, factsheet={"typeSpecification": {"maxLoadMass": max_mass}}
        )

    near_weak, far_strong = vehicle("A1.3", 500), vehicle("A5.0", 1500)
    LoadCarrier.objects.create(load_id="PAL-9", load_type="EPAL", weight=900)
    heavy = services.create_transport_order(
        source=station("PICK-1"), destination=station("DROP-1"), load_id="PAL-9"
    )

    services.dispatch_pending_orders()

    heavy.refresh_from_db()
    assert heavy.vehicle == far_strong
    assert not TransportOrder.objects.filter(vehicle=near_weak).exists()

    far_strong.operating_mode = "MANUAL"  # now only the weak one is idle
    far_strong.save()
    LoadCarrier.objects.create(load_id="PAL-10", load_type="EPAL", weight=900)
    waiting = services.create_transport_order(
        source=station("PICK-2"), destination=station("DROP-1"), load_id="PAL-10"
    )
    services.dispatch_pending_orders()
    waiting.refresh_from_db()
    assert waiting.status == TransportOrder.Status.NEW
    assert waiting.dispatch_note == "no idle vehicle can handle a load of 900 kg (at most 500 kg)"


def test_legs_with_a_load_avoid_edges_closed_to_loaded_vehicles() -> None:
    # V → P (pick) → D (drop): P→D is short but closed to loaded vehicles; P→M→D is open.
    nodes = [GraphNode("V", 0, 0), GraphNode("P", 1, 0), GraphNode("M", 2, 1), GraphNode("D", 3, 0)]
    rules = {"T": EdgeRule()}
    closed = {"T": EdgeRule(loaded=False)}
    edges = [
        GraphEdge("V-P", "V", "P", 1.0, rules=rules),
        GraphEdge("P-D", "P", "D", 2.0, rules=closed),
        GraphEdge("P-M", "P", "M", 1.5, rules=rules),
        GraphEdge("M-D", "M", "D", 1.5, rules=rules),
    ]
    graph = RoutingGraph(nodes, edges)
    vehicle = SimpleNamespace(last_node_id="V")
    steps = [
        SimpleNamespace(station=SimpleNamespace(node=SimpleNamespace(node_id=node)), operation=op)
        for node, op in (("P", OrderStep.Operation.PICK), ("D", OrderStep.Operation.DROP))
    ]
    empty = VehicleProfile(vehicle_type="T")
    loaded = capability.loaded(empty, FACTSHEET, "EPAL")

    assert loaded.loaded is True
    assert loaded.load_set == "pallet"
    assert route_through_steps(graph, vehicle, steps, empty) == (["V", "P", "D"], [1, 2])
    assert route_through_steps(graph, vehicle, steps, empty, loaded) == (
        ["V", "P", "M", "D"],
        [1, 3],
    )
