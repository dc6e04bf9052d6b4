"""What `control` exchanges with its database side, as plain data (no ORM here)."""

from dataclasses import dataclass, field
from typing import Any, Protocol

from control.execution import LayoutIndex, Progress, StepPlan
from control.live import InstantActionTrack, LiveVehicle


@dataclass(frozen=True)
class ActiveOrder:
    """An assigned transport order as `control` needs it (read from the database by the store)."""

    transport_order_id: int
    vda_order_id: str
    vehicle_pk: int
    route: list[str]
    pickup_node: str
    map_id: str
    pick_station: str
    drop_station: str
    load_id: str = ""
    load_type: str = "EPAL"
    cancel_requested: bool = False
    # "charge": a battery charge session ending in startCharging; "park": a drive to a park
    # or maintenance station (maintenance.ServiceMove). Both have negative ids (persistence).
    kind: str = "transport"
    # The stops in order (route index, action); empty: pick at pickup_node, drop at the end.
    steps: tuple[StepPlan, ...] = ()


@dataclass
class FlushBatch:
    """What the flusher writes in one go."""

    new_vehicles: list[LiveVehicle] = field(default_factory=list)
    snapshots: list[dict[str, Any]] = field(default_factory=list)
    factsheets: dict[int, dict[str, Any]] = field(default_factory=dict)
    progress: list[Progress] = field(default_factory=list)
    command_outcomes: list[InstantActionTrack] = field(default_factory=list)
    newly_available: int = 0
    job_requests: list[dict[str, Any]] = field(default_factory=list)  # vehicle.charge/.park
    traffic_waits: list[dict[str, Any]] = field(default_factory=list)  # control.wait_log


class Store(Protocol):
    """The database side of `control` (see control.persistence.DjangoStore)."""

    def load_layouts(self) -> dict[str, LayoutIndex]: ...
    def load_vehicles(self) -> list[dict[str, Any]]: ...
    def active_orders(self) -> list[ActiveOrder]: ...
    def flush(self, batch: FlushBatch) -> dict[tuple[str, str], int]: ...
    def request_dispatch(self) -> None: ...
    def vehicle_dialects(self) -> dict[int, str]: ...
    def layouts_revision(self) -> object: ...
