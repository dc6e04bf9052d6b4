"""Framework-free VDA 5050 vehicle simulator: N virtual AGVs over MQTT in one process.

Vehicles speak 2.0.0, 2.1.0 or 3.0.0 (``--version``): the vehicle logic is shared and works
on the 2.x Structs; :mod:`simulator.wire` converts at the message edge for 3.0.

Only the :mod:`vda5050` package, paho-mqtt and the standard library may be imported here
(an import-linter contract forbids Django, Celery, Channels and the project's apps).
"""

from __future__ import annotations

from simulator.fleet import FleetConfig, SimulatedFleet
from simulator.layout import Layout, LayoutError, LayoutNode, load_layout
from simulator.misbehaviour import Misbehaviour
from simulator.vehicle import StartPose, VehicleConfig, VirtualVehicle

__all__ = [
    "FleetConfig",
    "SimulatedFleet",
    "Layout",
    "LayoutError",
    "LayoutNode",
    "Misbehaviour",
    "StartPose",
    "VehicleConfig",
    "VirtualVehicle",
    "load_layout",
]
