"""Traffic waits as episodes: when traffic management holds a vehicle at its decision point, for
how long, where and for whom. The flusher looks at every vehicle about once a second; a wait
ends when the vehicle is no longer held (or moved on to another node), and the finished episode
goes to the database with the next flush (control.persistence hands it to the reports app)."""

from dataclasses import dataclass, field
from datetime import UTC, datetime
from typing import Any

from control.live import LiveVehicle


@dataclass
class OpenWait:
    """A wait in progress."""

    started_at: datetime
    node_id: str
    map_id: str
    x: float | None
    y: float | None
    waited_for: dict[str, None] = field(default_factory=dict)  # ordered set of serials


class WaitLog:
    """Turns "whom does this vehicle wait for now" samples into finished wait episodes."""

    def __init__(self) -> None:
        self.open: dict[int, OpenWait] = {}
        self.finished: list[dict[str, Any]] = []

    def observe(
        self, vehicle: LiveVehicle, waiting_for: list[str], now: datetime | None = None
    ) -> None:
        """Start, extend or end the vehicle's wait from one sample of whom it waits for."""
        if vehicle.pk is None or not (waiting_for or vehicle.pk in self.open):
            return  # the usual case, about once a second for every vehicle: nothing to do
        now = now or datetime.now(UTC)
        state, position = vehicle.state, vehicle.visual_position
        node_id = state.last_node_id if state is not None else ""
        current = self.open.get(vehicle.pk)
        if current is not None and (not waiting_for or current.node_id != node_id):
            self._close(vehicle.pk, now)
            current = None
        if not waiting_for:
            return
        if current is None:
            current = self.open[vehicle.pk] = OpenWait(
                started_at=now,
                node_id=node_id,
                map_id=position.map_id if position else "",
                x=position.x if position else None,
                y=position.y if position else None,
            )
        current.waited_for.update(dict.fromkeys(waiting_for))

    def _close(self, pk: int, now: datetime) -> None:
        wait = self.open.pop(pk)
        self.finished.append(
            {
                "vehicle_id": pk,
                "map_id": wait.map_id,
                "node_id": wait.node_id,
                "x": wait.x,
                "y": wait.y,
                "started_at": wait.started_at,
                "seconds": (now - wait.started_at).total_seconds(),
                "waited_for": list(wait.waited_for),
            }
        )

    def take_finished(self) -> list[dict[str, Any]]:
        """The finished episodes since the last call (for the flush)."""
        finished, self.finished = self.finished, []
        return finished
