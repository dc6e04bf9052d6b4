"""Acceptance (issue 7): 10 vehicles, 2 shared chargers, continuous orders for 8 simulated hours
with the real policy, charger assignment and dispatch decisions (bench/energy.py)."""

from battery.policy import Levels
from bench.energy import simulate
from simulator.config import VehicleConfig


def test_eight_hours_with_two_shared_chargers_keep_every_vehicle_above_critical() -> None:
    levels = Levels()
    run = simulate(vehicles=10, hours=8.0, seed=3, levels=levels)
    ignored = simulate(vehicles=10, hours=8.0, seed=3, charging=False)

    assert run.min_charge >= levels.critical
    assert run.max_per_point == 1  # never two vehicles on one charging point
    assert run.charge_sessions > 50  # the chargers were really shared
    rho = run.finished / ignored.finished
    print(f"rho_energy={rho:.3f} finished={run.finished} ignored={ignored.finished}")
    assert 0.5 < rho < 1.0


def test_without_a_working_minimum_vehicles_would_run_flat() -> None:
    """The property above can fail: with the levels squeezed to nothing, batteries empty."""
    careless = Levels(critical=1, needs_charge=1.5, sufficient=2, charge_until=3, full=4)
    run = simulate(
        vehicles=10,
        hours=1.0,
        seed=3,
        levels=careless,
        battery=VehicleConfig(battery_charge_per_second=0.25),
    )
    assert run.min_charge < Levels().critical
