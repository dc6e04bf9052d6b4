"""The pure parts of traffic in `control`: footprints from factsheets, the layout, windows.

Used by `control.traffic_link`; no state here.
"""

import math
from collections import deque
from collections.abc import Iterable
from dataclasses import dataclass, field
from typing import Any

import vda5050
from control.execution import LayoutIndex, Window
from control.live import LiveVehicle
from control.session import Link
from traffic import Layout, VehicleClass

# A vehicle without a factsheet is planned with this footprint (the simulator's size, 1.2 × 0.8 m).
DEFAULT_CLASS = VehicleClass("default", length=1.2, width=0.8, speed=1.0)
AUTOMATIC = frozenset({"AUTOMATIC", "SEMIAUTOMATIC"})
DWELL = 2.0  # seconds planned for a pick or drop (timing only; safety never depends on it)


def vehicle_class(factsheet: dict[str, Any] | None) -> VehicleClass:
    """The footprint and speed of a vehicle from its factsheet, or default (REFERENCE J.43,
    J.46): physicalParameters length × width and speedMax, enlarged to cover every 2D envelope
    of agvGeometry (a load or a sensor field may stick out beyond the vehicle's body)."""
    physical = (factsheet or {}).get("physicalParameters") or (factsheet or {}).get(
        "physical_parameters"
    )
    if not isinstance(physical, dict):
        return DEFAULT_CLASS
    length, width = physical.get("length"), physical.get("width")
    speed = physical.get("speedMax", physical.get("speed_max"))
    if not all(isinstance(v, int | float) and v > 0 for v in (length, width)):
        return DEFAULT_CLASS
    outline_length, outline_width = envelope_extent(factsheet)
    return VehicleClass(
        "factsheet",
        length=max(float(length), outline_length),  # type: ignore[arg-type]
        width=max(float(width), outline_width),  # type: ignore[arg-type]
        speed=float(speed) if isinstance(speed, int | float) and speed > 0 else 1.0,
    )


def envelope_extent(factsheet: dict[str, Any] | None) -> tuple[float, float]:
    """Length and width of the rectangle centred on the kinematic centre (traffic's footprint)
    that covers every agvGeometry 2D envelope polygon, of all sets; (0, 0) without any.
    Centred, so an envelope reaching further forward than back still fits."""
    geometry = (factsheet or {}).get("agvGeometry") or (factsheet or {}).get("agv_geometry")
    envelopes = geometry.get("envelopes2d") if isinstance(geometry, dict) else None
    xs, ys = [0.0], [0.0]
    for outline in envelopes if isinstance(envelopes, list) else []:
        if not isinstance(outline, dict):
            continue
        points = outline.get("polygonPoints", outline.get("polygon_points"))
        for point in points if isinstance(points, list) else []:
            x, y = (point.get("x"), point.get("y")) if isinstance(point, dict) else (None, None)
            if isinstance(x, int | float) and isinstance(y, int | float):
                xs.append(abs(float(x)))
                ys.append(abs(float(y)))
    return 2 * max(xs), 2 * max(ys)


def envelope(classes: Iterable[VehicleClass]) -> VehicleClass:
    """One class covering all: the largest footprint, the slowest speed (conservative)."""
    found = list(classes) or [DEFAULT_CLASS]
    return VehicleClass(
        "envelope",
        length=max(c.length for c in found),
        width=max(c.width for c in found),
        margin=max(c.margin for c in found),
        speed=min(c.speed for c in found),
    )


def layout_of(index: LayoutIndex) -> Layout:
    """The traffic layout of a control layout index (lengths from positions, zone speed limits)."""
    nodes = [(node_id, place.x, place.y) for node_id, place in index.nodes.items()]
    edges = []
    for (start, end), edge_id in index.edges.items():
        a, b = index.nodes.get(start), index.nodes.get(end)
        if a is None or b is None:
            continue
        length = math.hypot(b.x - a.x, b.y - a.y) or None
        if length is None:
            continue  # a zero-length edge cannot be planned on
        edges.append((start, end, length, index.speed_limits.get(edge_id)))
    return Layout(nodes, edges)


def window(
    route_length: int,
    first: int,
    base_end: int,
    max_nodes: int | None,
    horizon: int | None = None,
) -> Window:
    """The route indices a message carries from `first`, released up to `base_end` at most,
    with at most `horizon` unreleased nodes after the base (None: the rest of the route)."""
    end = route_length - 1
    last = end if max_nodes is None else min(end, first + max(max_nodes, 2) - 1)
    released = max(first, min(last, base_end))
    if horizon is not None:
        last = min(last, released + horizon)
    return Window(first=first, last=last, released=released)


def blocking_reason(vehicle: LiveVehicle, state: vda5050.State | None, now: float) -> str | None:
    """Why a vehicle must be a static obstacle now (None: it follows its plan)."""
    if vehicle.session.link(now) is not Link.ONLINE:
        return "offline"
    if state is None:
        return "no state"
    if str(state.operating_mode) not in AUTOMATIC:
        return f"{state.operating_mode} mode"
    if any(str(e.error_level) == "FATAL" for e in state.errors):
        return "fatal error"
    return None


@dataclass
class Stats:
    """Release-decision timing of the hot path (for benchmarks and the live page)."""

    decisions: int = 0
    seconds: float = 0.0
    worst: float = 0.0
    samples: list[float] = field(default_factory=list)

    def add(self, seconds: float) -> None:
        self.decisions += 1
        self.seconds += seconds
        self.worst = max(self.worst, seconds)
        if len(self.samples) < 100_000:
            self.samples.append(seconds)


@dataclass
class Tracked:
    """One vehicle under traffic control."""

    vehicle: LiveVehicle
    map_id: str
    order_id: str | None = None  # the VDA 5050 order the manager's plan belongs to
    static: str | None = None  # why it is a static obstacle
    # An order driven while traffic lost track of it (blocked mid-order, adopted after a
    # restart): it gets no more base until the vehicle stops at its decision point and is
    # planned again from there, route index `offset` of the order being index 0 of the plan.
    lost: str | None = None
    offset: int = 0
    # The last few things the link did with this vehicle (monotonic time, what), logged with
    # a problem such as progress beyond the base, so that the log says how it came about.
    trail: deque[tuple[float, str]] = field(default_factory=lambda: deque(maxlen=12))

    def note(self, now: float, what: str) -> None:
        """Remember one event for the trail."""
        self.trail.append((now, what))

    def history(self, now: float) -> str:
        """The trail as text, newest last, times in seconds before `now`."""
        return "; ".join(f"-{now - t:.1f}s {what}" for t, what in self.trail)


def name(vehicle: LiveVehicle) -> str:
    """The traffic manager's id of a vehicle."""
    return f"{vehicle.manufacturer}/{vehicle.serial_number}"
