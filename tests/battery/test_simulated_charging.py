"""The charge session's order and stopCharging as control builds them, on a simulated vehicle:
it drives to the point, charges there, and stops when told."""

from control.execution import OrderExecution
from control.order_messages import LoadJob, _node_actions
from tests.simulator.builders import (
    action,
    finished,
    instant,
    make_order,
    make_vehicle,
    run,
    run_until,
)


def test_the_simulator_charges_at_the_end_of_a_charge_order_until_stopped() -> None:
    execution = OrderExecution.plan(
        transport_order_id=-2, vda_order_id="CS-1", route=["n1", "n2", "n3"], kind="charge"
    )
    job = LoadJob("", "", "CHARGE-1", "CHARGE-1")
    actions = {n: _node_actions(execution, i, job) for i, n in enumerate(execution.route)}
    assert actions["n1"] == actions["n2"] == []
    vehicle = make_vehicle(battery_start=40.0, battery_charge_per_second=1.0)

    vehicle.on_order(make_order("CS-1", execution.route, actions=actions))
    run_until(vehicle, finished)
    assert vehicle.last_node_id == "n3"
    assert vehicle.charging
    charged_from = vehicle.battery
    run(vehicle, 5.0)
    assert vehicle.battery > charged_from

    vehicle.on_instant_actions(instant(action("stopCharging", "stop-1")))
    run(vehicle, 2.0)
    assert not vehicle.charging
