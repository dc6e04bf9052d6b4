"""Master-control rules on the vehicle's state and factsheet (REFERENCE F.32, F.34, J.42, J.43,
J.46): omitted loads are unknown, no new order while the vehicle reports charging, the vehicle
type from typeSpecification, heights, footprints and speeds from physicalParameters and
agvGeometry."""

# The controller fixtures (and the per-version parametrisation) are those of test_controller.py.
# ruff: noqa: F811

import json
from typing import Any

import msgspec
import pytest

from control.live import LiveVehicle
from control.snapshots import row
from control.traffic_link import TrafficLink
from control.traffic_support import DEFAULT_CLASS, vehicle_class
from inventory.models import Discrepancy, LoadCarrier
from inventory.services.observe import LoadObserver
from maps.models import Edge, EdgeProperty, NodeProperty, Station, VehicleType
from maps.services import mark_layout_changed
from orders import capability, selectors, services
from orders.models import TransportOrder
from orders.services import StepSpec
from tests.control import fakes
from tests.control.fakes import order, state
from tests.control.test_controller import (  # noqa: F401 - fixtures
    controller,
    orders_in,
    protocol_version,
    sent,
)
from tests.factories import VehicleFactory
from tests.traffic.test_link import LAYOUTS
from tests.traffic.test_link import state as traffic_state


def charging(message: bytes) -> bytes:
    """The encoded state `message` with charging true (2.x batteryState, 3.0 powerSupply)."""
    data = json.loads(message)
    data["powerSupply" if "powerSupply" in data else "batteryState"]["charging"] = True
    return json.dumps(data).encode()


# -- F.32 loads omitted = unknown ------------------------------------------------------------


def test_F32_the_snapshot_tells_omitted_loads_from_no_loads() -> None:
    vehicle = LiveVehicle("sim", "AGV-1", "uagv")
    vehicle.state = traffic_state("AGV-1", "C")  # a state without `loads`
    assert (row(vehicle)["loads"], row(vehicle)["loads_known"]) == ([], False)

    vehicle.state = msgspec.structs.replace(vehicle.state, loads=[])
    assert (row(vehicle)["loads"], row(vehicle)["loads_known"]) == ([], True)


def test_F32_omitted_loads_never_count_as_a_missing_load(db: None) -> None:
    vehicle = VehicleFactory()
    LoadCarrier.objects.create(load_id="L-1", vehicle=vehicle)
    now = [0.0]
    observer = LoadObserver(clock=lambda: now[0])

    def flush(at: float, **snapshot: Any) -> int:
        now[0] = at
        return observer.observe([{"pk": vehicle.pk, "last_seen": at, "loads": [], **snapshot}])

    assert [flush(t, loads_known=False) for t in (0.0, 60.0, 120.0)] == [0, 0, 0]
    assert not Discrepancy.objects.exists()
    # The same vehicle reporting `loads: []` (unloaded) is missing L-1 after the grace time.
    assert [flush(t, loads_known=True) for t in (180.0, 240.0)] == [0, 1]
    assert Discrepancy.objects.get().kind == Discrepancy.Kind.MISSING_LOAD


# -- F.34 charging ---------------------------------------------------------------------------


def test_F34_no_new_order_while_the_vehicle_reports_charging(controller, sent) -> None:
    controller.handle_message(fakes.topic(), charging(state(header_id=1)))
    controller.sync([order()])
    assert orders_in(sent) == []
    assert not controller.fleet.by_pk(1).is_available

    # stopCharging done: the vehicle reports charging false once it can take orders again.
    controller.handle_message(fakes.topic(), state(header_id=2))
    controller.sync([order()])
    assert [m["orderId"] for m in orders_in(sent)] == ["TO-7"]


# -- J.42 type specification -----------------------------------------------------------------


def test_J42_the_vehicle_type_comes_from_the_factsheet_series_name(db: None) -> None:
    lif_id = VehicleType.objects.create(type_id="acme.Carrier")
    bare_id = VehicleType.objects.create(type_id="Tugger")
    by_series = VehicleType.objects.create(type_id="t3", manufacturer="acme", series_name="Lift")

    def vehicle(series: str | None) -> Any:
        factsheet = None if series is None else {"typeSpecification": {"seriesName": series}}
        return VehicleFactory(manufacturer="acme", factsheet=factsheet)

    carrier, tugger, lift, unknown, none = (
        vehicle(s) for s in ("Carrier", "Tugger", "Lift", "Other", None)
    )

    found = selectors.get_vehicle_types(vehicles=[carrier, tugger, lift, unknown, none])

    assert found == {carrier.pk: lif_id, tugger.pk: bare_id, lift.pk: by_series}


def test_J42_dispatch_routes_a_vehicle_by_the_type_its_factsheet_names(
    demo_map, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setattr("orders.services.dispatch.send_command", lambda kind, **payload: None)
    small = VehicleType.objects.create(type_id="sim.Small", series_name="Small")
    VehicleType.objects.create(type_id="sim.Big", series_name="Big")
    pick = Station.objects.get(map=demo_map, station_id="PICK-3")
    NodeProperty.objects.create(node=pick.node, vehicle_type=small)  # PICK-3: Small only
    mark_layout_changed(maps=[demo_map])
    # Without the node property the nearer Big one would get the order.
    big = VehicleFactory(
        last_node_id="A5.3", factsheet={"typeSpecification": {"seriesName": "Big"}}
    )
    far_small = VehicleFactory(
        last_node_id="A0.0", factsheet={"typeSpecification": {"seriesName": "Small"}}
    )
    drop = Station.objects.get(map=demo_map, station_id="DROP-1")
    transport = services.create_transport_order(
        steps=[StepSpec(station=pick, operation="PICK"), StepSpec(station=drop, operation="DROP")]
    )

    services.dispatch_pending_orders()

    transport.refresh_from_db()
    assert transport.status == TransportOrder.Status.ASSIGNED
    assert transport.vehicle == far_small
    assert not big.transport_orders.exists()


# -- J.43 physical parameters, J.46 geometry ----------------------------------------------------


def test_J43_dispatch_keeps_a_vehicle_under_edges_lower_than_its_factsheet_height(
    demo_map, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setattr("orders.services.dispatch.send_command", lambda kind, **payload: None)
    carrier = VehicleType.objects.create(type_id="sim.Carrier", series_name="Carrier")
    pick = Station.objects.get(map=demo_map, station_id="PICK-3")
    for edge in Edge.objects.filter(end=pick.node):  # a 1.5 m passage into PICK-3
        EdgeProperty.objects.create(edge=edge, vehicle_type=carrier, max_height=1.5)
    mark_layout_changed(maps=[demo_map])

    def vehicle(node: str, height: float) -> Any:
        factsheet = {
            "typeSpecification": {"seriesName": "Carrier"},
            "physicalParameters": {"heightMax": height},
        }
        return VehicleFactory(last_node_id=node, factsheet=factsheet)

    tall, low = vehicle("A5.3", 2.0), vehicle("A0.0", 1.2)  # the tall one is nearer
    drop = Station.objects.get(map=demo_map, station_id="DROP-1")
    transport = services.create_transport_order(
        steps=[StepSpec(station=pick, operation="PICK"), StepSpec(station=drop, operation="DROP")]
    )

    services.dispatch_pending_orders()

    transport.refresh_from_db()
    assert transport.vehicle == low
    assert not tall.transport_orders.exists()


def box(half_length: float, half_width: float, front: float | None = None) -> list[dict]:
    """Polygon points of a rectangle around the kinematic centre (front: reach ahead)."""
    ahead = half_length if front is None else front
    return [
        {"x": ahead, "y": half_width},
        {"x": -half_length, "y": half_width},
        {"x": -half_length, "y": -half_width},
        {"x": ahead, "y": -half_width},
    ]


PHYSICAL = {"length": 1.0, "width": 0.6, "speedMax": 1.5}


def test_J46_the_footprint_covers_every_2d_envelope_of_the_geometry() -> None:
    inside = {"envelopes2d": [{"set": "default", "polygonPoints": box(0.4, 0.2)}]}
    loaded = {
        "envelopes2d": [
            {"set": "default", "polygonPoints": box(0.5, 0.3)},
            # a pallet sticking out 0.9 m ahead: centred on the kinematic centre, 1.8 m long
            {"set": "loaded", "polygonPoints": box(0.5, 0.45, front=0.9)},
        ]
    }

    smaller = vehicle_class({"physicalParameters": PHYSICAL, "agvGeometry": inside})
    larger = vehicle_class({"physicalParameters": PHYSICAL, "agvGeometry": loaded})

    assert (smaller.length, smaller.width, smaller.speed) == (1.0, 0.6, 1.5)  # the body counts
    assert (larger.length, larger.width, larger.speed) == (1.8, 0.9, 1.5)
    broken = {"envelopes2d": [{"set": "x", "polygonPoints": [{"x": "far"}]}, "junk"]}
    assert vehicle_class({"physicalParameters": PHYSICAL, "agvGeometry": broken}).length == 1.0


def fleet_vehicle(serial: str, factsheet: dict | None) -> LiveVehicle:
    vehicle = LiveVehicle("sim", serial, "uagv")
    vehicle.factsheet = factsheet
    return vehicle


def test_J43_traffic_plans_with_the_fleets_largest_footprint_and_slowest_speed() -> None:
    long_fast = {"physicalParameters": {"length": 1.6, "width": 0.7, "speedMax": 2.0}}
    wide_slow = {
        "physicalParameters": {"length": 0.9, "width": 0.6, "speedMax": 0.5},
        "agvGeometry": {"envelopes2d": [{"set": "default", "polygonPoints": box(0.45, 0.55)}]},
    }
    fleet = [
        fleet_vehicle("A", long_fast),
        fleet_vehicle("B", wide_slow),
        fleet_vehicle("C", None),  # no factsheet yet: the default footprint
    ]
    link = TrafficLink(lambda: fleet)

    link.set_layouts(LAYOUTS)

    (planned,) = link.managers["m"].classes
    assert (planned.length, planned.width, planned.speed) == (1.6, 1.1, 0.5)
    assert planned.length > DEFAULT_CLASS.length  # the fleet, not the default, decides


def test_J46_below_the_factsheets_critical_charge_level_no_transport_order(
    controller, demo_map, monkeypatch: pytest.MonkeyPatch
) -> None:
    import vda5050
    from simulator import wire
    from simulator.vehicle import StartPose, VehicleConfig, VirtualVehicle

    monkeypatch.setattr("orders.services.dispatch.send_command", lambda kind, **payload: None)
    simulated = VirtualVehicle(
        VehicleConfig(version=fakes.PROTOCOL["version"]), StartPose("demo", "a", 0.0, 0.0)
    )
    factsheet = json.loads(vda5050.encode(wire.factsheet(simulated)))
    if fakes.PROTOCOL["version"].startswith("3."):
        factsheet.setdefault("mobileRobotConfiguration", {})["batteryCharging"] = {
            "criticalLowChargingLevel": 70.0
        }
    controller.handle_message(fakes.topic(kind="factsheet"), json.dumps(factsheet).encode())
    stored = controller.fleet.vehicles[("sim", "AGV-1")].factsheet
    critical = capability.critical_charge(stored)
    assert critical == (70.0 if fakes.PROTOCOL["version"].startswith("3.") else None)

    low = VehicleFactory(last_node_id="A1.3", battery_charge=60.0, factsheet=stored)
    pick, drop = (Station.objects.get(map=demo_map, station_id=s) for s in ("PICK-1", "DROP-1"))
    transport = services.create_transport_order(source=pick, destination=drop)
    services.dispatch_pending_orders()
    transport.refresh_from_db()
    if critical is None:
        assert transport.vehicle == low
    else:
        assert transport.status == TransportOrder.Status.NEW
        assert "below its critical charge level" in transport.dispatch_note


def test_J46_edges_driven_with_the_load_keep_to_the_load_sets_speed_limit(controller, sent) -> None:
    from dataclasses import replace

    from control.capabilities import Capabilities
    from tests.control.fakes import LINE

    controller.layouts["demo"] = replace(LINE, speed_limits={"bc": 0.5, "ab": 0.2})
    controller.handle_message(fakes.topic(), state(header_id=1))
    vehicle = controller.fleet.by_pk(1)
    vehicle.capabilities = Capabilities({}, optional_parameters=frozenset({"order.edges.maxSpeed"}))
    vehicle.factsheet = {
        "loadSpecification": {
            "loadSets": [{"setName": "pallet", "loadType": "EPAL", "agvSpeedLimit": 0.3}]
        }
    }

    controller.sync([order(load_type="EPAL")])  # a → b (pick) → c → d (drop)

    (message,) = orders_in(sent)
    speeds = [e.get("maxSpeed", e.get("maximumSpeed")) for e in message["edges"]]
    assert speeds == [0.2, 0.3, 0.3]  # empty: the edge's own limit; loaded: the slower one
