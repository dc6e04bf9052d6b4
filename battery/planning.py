"""Charger assignment and queueing as pure logic (no Django): who gets which charging point.

Requests are served in urgency order (critical, needs charge, staff, opportunity; then the
lowest charge, then the longest waiting); each takes the nearest free compatible point it can
reach. A point is given to one vehicle at a time: the services hold the booking from assignment
until the vehicle left the charger, and the database refuses a second booking.
"""

from collections.abc import Callable, Sequence
from dataclasses import dataclass, field

from battery.policy import URGENCY, Reason

DistancesTo = Callable[[str], dict[str, float]]


@dataclass(frozen=True)
class ChargePoint:
    """A free charging point: charger id, point index, the node to drive to, and the vehicle
    types it takes (None: any)."""

    charger: int
    point: int
    node: str
    types: frozenset[str] | None = None


@dataclass(frozen=True)
class ChargeRequest:
    """A vehicle waiting to charge: where it stands, its charge and why it must charge."""

    key: int
    node: str
    charge: float
    reason: Reason
    vehicle_type: str | None = None
    since: float = 0.0  # queued at (any monotonic number, for fairness)


@dataclass
class ChargePlan:
    """Points given now, and the queue position of every request that waits."""

    assigned: list[tuple[ChargeRequest, ChargePoint, float]] = field(default_factory=list)
    queue: dict[int, int] = field(default_factory=dict)


def queue_order(request: ChargeRequest) -> tuple[int, float, float, int]:
    return (URGENCY[request.reason], request.charge, request.since, request.key)


def assign_points(
    requests: Sequence[ChargeRequest], free: Sequence[ChargePoint], distances_to: DistancesTo
) -> ChargePlan:
    """Give free points to the most urgent requests, nearest point first."""
    plan = ChargePlan()
    available = list(free)
    distances: dict[str, dict[str, float]] = {}
    position = 0
    for request in sorted(requests, key=queue_order):
        options = []
        for point in available:
            if point.types is not None and request.vehicle_type not in point.types:
                continue
            if point.node not in distances:
                distances[point.node] = distances_to(point.node)
            distance = distances[point.node].get(request.node)
            if distance is not None:
                options.append((distance, point.charger, point.point, point))
        if options:
            distance, _, _, point = min(options, key=lambda option: option[:3])
            plan.assigned.append((request, point, distance))
            available.remove(point)
        else:
            position += 1
            plan.queue[request.key] = position
    return plan
