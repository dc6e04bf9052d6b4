"""Load-handling faults of a simulated vehicle, for inventory and alert tests (issue 8).

Framework-free like the rest of the simulator. A :class:`LoadFaults` is applied after each
tick of its vehicle (``faults.after_tick(vehicle, loads_before)``) and changes only what the
vehicle *reports* in ``state.loads``, the way real load sensors go wrong:

- ``phantom``: report a load nobody put there (a misread or a forgotten pallet);
- ``empty_picks``: the next N picks finish but the fork comes up empty;
- ``lose``: the carried load vanishes (fell off, sensor dropped out).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

from vda5050 import Load

if TYPE_CHECKING:
    from simulator.vehicle import VirtualVehicle


@dataclass
class LoadFaults:
    """What goes wrong with one vehicle's loads; the default instance changes nothing."""

    phantom: str | None = None
    """loadId of a load the vehicle reports from the next tick on (once)."""
    empty_picks: int = 0
    """How many of the next picks come up empty."""
    lose: bool = False
    """Drop the carried load from the report at the next tick (once)."""

    def after_tick(self, vehicle: VirtualVehicle, loads_before: list[Load]) -> None:
        """Apply the armed faults to what the vehicle reports now."""
        picked = not loads_before and bool(vehicle.loads)
        if picked and self.empty_picks > 0:
            self.empty_picks -= 1
            vehicle.loads = []
            vehicle.mark_state_due()
        if self.lose and vehicle.loads:
            self.lose = False
            vehicle.loads = []
            vehicle.mark_state_due()
        if self.phantom is not None:
            vehicle.loads = [*vehicle.loads, Load(load_id=self.phantom, load_type="EPAL")]
            self.phantom = None
            vehicle.mark_state_due()

    @staticmethod
    def take_off(vehicle: VirtualVehicle, load_id: str) -> None:
        """A person takes the load off the vehicle: it no longer reports it."""
        vehicle.loads = [load for load in vehicle.loads if load.load_id != load_id]
        vehicle.mark_state_due()
