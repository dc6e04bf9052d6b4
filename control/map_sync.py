"""Map distribution to VDA 5050 2.1/3.0 vehicles (REFERENCE K.47), on the live model only.

For every map a vehicle reports in `state.maps` (or stands on) and that has a distributed
release, bring the vehicle onto the released version, one instant action at a time and each
followed to its end in the state: `downloadMap` (the vehicle pulls the file from the release's
link), `enableMap` once it is listed DISABLED, then `deleteMap` of other DISABLED versions of
that map. An action that fails, is refused or stays unanswered for `RETRY_AFTER` seconds is
retried; after `MAX_FAILURES` failures reported by the vehicle the map is FAILED with its reason
until the release changes (our own refusals, e.g. a mode without actions, are retried after
`RETRY_AFTER` without counting). enableMap and deleteMap wait until the vehicle is idle (E.23).
Only vehicles whose factsheet declares downloadMap and enableMap get distributions; the others
are shown UNSUPPORTED.

Orders (K.47 "every order mapId must be ENABLED"): a vehicle that reports `state.maps` gets a
new order only if the order's map is ENABLED on it and, when it supports distribution, in the
released version; otherwise the order waits and the reason is kept (`hold_reason`, persisted
with the status). Vehicles that do not report `state.maps` (2.0) are not held.
"""

import time
from collections import Counter
from collections.abc import Callable, Iterable
from dataclasses import dataclass
from typing import Any

from control.capabilities import Capabilities
from control.live import InstantActionTrack, LiveVehicle, VehicleKey
from vda5050.enums import ActionScope

SendAction = Callable[[LiveVehicle, str, dict[str, Any]], InstantActionTrack]
_UNDERWAY = frozenset({"SENT", "WAITING", "INITIALIZING", "RUNNING", "PAUSED"})
_STEP = {"downloadMap": "DOWNLOADING", "enableMap": "ENABLING", "deleteMap": "DELETING"}


@dataclass(frozen=True)
class MapTarget:
    """A distributed release: the version vehicles must enable and where they fetch it."""

    map_id: str
    version: str
    link: str
    checksum: str = ""


@dataclass
class MapStatus:
    """One map on one vehicle, as `control.models.VehicleMap` stores it."""

    map_id: str
    released_version: str
    enabled_version: str
    status: str
    reason: str = ""
    reported: tuple[tuple[str, str], ...] = ()  # (version, mapStatus) of this map

    def row(self) -> dict[str, Any]:
        return {
            "released_version": self.released_version,
            "enabled_version": self.enabled_version,
            "status": self.status,
            "reason": self.reason[:500],
            "reported": [{"mapVersion": v, "mapStatus": s} for v, s in self.reported],
        }


@dataclass
class _Pending:
    action_type: str
    version: str
    track: InstantActionTrack
    sent_at: float


def supports_distribution(capabilities: Capabilities | None) -> bool:
    """The factsheet declares instant downloadMap and enableMap (E.25: send only those)."""
    if capabilities is None:
        return False
    return all(
        (spec := capabilities.actions.get(kind)) is not None
        and ActionScope.INSTANT in spec.action_scopes
        for kind in ("downloadMap", "enableMap")
    )


class MapSync:
    """Drives downloadMap → enableMap → deleteMap per vehicle and map; holds orders meanwhile."""

    RETRY_AFTER = 30.0  # s without an answer before an action is sent again
    MAX_FAILURES = 3

    def __init__(self, send: SendAction) -> None:
        self.send = send
        self.targets: dict[str, MapTarget] = {}
        self.statuses: dict[tuple[VehicleKey, str], MapStatus] = {}
        self.changed: set[tuple[VehicleKey, str]] = set()
        self._pending: dict[tuple[VehicleKey, str], _Pending] = {}
        self._failures: Counter[tuple[VehicleKey, str, str]] = Counter()
        self.hold_reason: dict[VehicleKey, str] = {}
        # What each vehicle's last step saw; an unchanged state needs no new step (hot path).
        self._seen: dict[VehicleKey, tuple[object, ...]] = {}
        self._generation = 0  # counts target changes

    def set_targets(self, targets: dict[str, MapTarget], vehicles: Iterable[LiveVehicle]) -> None:
        """Take the current releases; a changed release starts the vehicles' steps at once."""
        if targets == self.targets:
            return
        self.targets = dict(targets)
        self._generation += 1
        for vehicle in vehicles:
            self.step(vehicle)

    def step(self, vehicle: LiveVehicle, now: float | None = None) -> None:
        """Send the next action this vehicle needs for each released map it uses."""
        state = vehicle.state
        if state is None or state.maps is None:
            return
        position = state.agv_position.map_id if state.agv_position is not None else None
        seen = (
            tuple(state.maps),
            position,
            self._generation,
            id(vehicle.capabilities),
            vehicle.is_idle,
        )
        if self._seen.get(vehicle.key) == seen and not any(
            k[0] == vehicle.key for k in self._pending
        ):
            return  # nothing changed since the last step and nothing is under way
        self._seen[vehicle.key] = seen
        now = time.monotonic() if now is None else now
        reported: dict[str, list[tuple[str, str]]] = {}
        for entry in state.maps:
            reported.setdefault(entry.map_id, []).append((entry.map_version, str(entry.map_status)))
        used = set(reported)
        if state.agv_position is not None:
            used.add(state.agv_position.map_id)
        for map_id in sorted(used):
            status = self._step_map(vehicle, map_id, reported.get(map_id, []), now)
            self._record(vehicle, status)

    def _step_map(
        self, vehicle: LiveVehicle, map_id: str, versions: list[tuple[str, str]], now: float
    ) -> MapStatus:
        enabled = next((v for v, s in versions if s == "ENABLED"), "")
        target = self.targets.get(map_id)
        status = MapStatus(map_id, "", enabled, "NO_RELEASE", "", tuple(versions))
        if target is None:
            return status
        status.released_version = target.version
        if not supports_distribution(vehicle.capabilities):
            status.status = "SYNCED" if enabled == target.version else "UNSUPPORTED"
            if status.status == "UNSUPPORTED":
                status.reason = "the factsheet declares no instant downloadMap/enableMap"
            return status
        key = (vehicle.key, map_id)
        pending = self._pending.get(key)
        if pending is not None:
            track = pending.track
            waiting = track.status in _UNDERWAY or track.status == "REFUSED"
            if waiting and now - pending.sent_at < self.RETRY_AFTER:
                status.status = _STEP[pending.action_type]
                status.reason = track.reason if track.status == "REFUSED" else ""
                return status
            del self._pending[key]
            if track.status not in {"FINISHED", "REFUSED"}:  # refusals are ours: no strike
                self._failures[(*key, target.version)] += 1
                status.reason = f"{pending.action_type} {track.status}: {track.reason}".strip()
        if self._failures[(*key, target.version)] >= self.MAX_FAILURES:
            status.status = "FAILED"
            status.reason = status.reason or self.statuses.get(key, status).reason
            return status
        have = dict(versions).get(target.version)
        if have is None:
            action, params = "downloadMap", self._download_params(vehicle, target)
        elif have == "DISABLED":
            action, params = "enableMap", {"mapId": map_id, "mapVersion": target.version}
        else:
            old = [v for v, s in versions if v != target.version and s == "DISABLED"]
            if not old:
                status.status = "SYNCED"
                return status
            action, params = "deleteMap", {"mapId": map_id, "mapVersion": old[0]}
        status.status = _STEP[action]
        if action != "downloadMap" and not vehicle.is_idle:
            # E.23: no map change under a running order; the vehicle gets no new one meanwhile.
            status.reason = f"{action} waits until the vehicle has finished its order"
            return status
        track = self.send(vehicle, action, params)
        if track.status == "REFUSED":
            status.reason = f"{action} refused: {track.reason}"
        self._pending[key] = _Pending(action, target.version, track, now)
        return status

    @staticmethod
    def _download_params(vehicle: LiveVehicle, target: MapTarget) -> dict[str, Any]:
        params: dict[str, Any] = {
            "mapId": target.map_id,
            "mapVersion": target.version,
            "mapDownloadLink": target.link,
        }
        spec = vehicle.capabilities.actions.get("downloadMap") if vehicle.capabilities else None
        declared = {p.key for p in (spec.action_parameters or [])} if spec else set()
        if target.checksum and "mapHash" in declared:
            params["mapHash"] = target.checksum  # optional: only to vehicles that declare it
        return params

    def _record(self, vehicle: LiveVehicle, status: MapStatus) -> None:
        key = (vehicle.key, status.map_id)
        if not status.reason and status.status != "SYNCED":
            status.reason = self.hold_reason.get(vehicle.key, "")
        if self.statuses.get(key) != status:
            self.statuses[key] = status
            self.changed.add(key)

    # Orders -------------------------------------------------------------------------------

    def order_refusal(self, vehicle: LiveVehicle, map_id: str) -> str | None:
        """Why a new order on `map_id` must not go to `vehicle` now, or None (K.47)."""
        state = vehicle.state
        if state is None or state.maps is None:
            return None
        enabled = [
            m.map_version
            for m in state.maps
            if m.map_id == map_id and str(m.map_status) == "ENABLED"
        ]
        if not enabled:
            return f"map {map_id} is not enabled on the vehicle"
        target = self.targets.get(map_id)
        if (
            target is not None
            and enabled[0] != target.version
            and supports_distribution(vehicle.capabilities)
        ):
            step = self.statuses.get((vehicle.key, map_id))
            doing = f" ({step.status.lower()})" if step is not None else ""
            return (
                f"vehicle has map {map_id} version {enabled[0]} enabled, "
                f"the released version is {target.version}{doing}"
            )
        return None

    def note_hold(self, vehicle: LiveVehicle, map_id: str, reason: str | None) -> None:
        """Keep why an order waits for this vehicle's map (shown with the map status)."""
        if reason is None:
            self.hold_reason.pop(vehicle.key, None)
            return
        self.hold_reason[vehicle.key] = reason
        key = (vehicle.key, map_id)
        status = self.statuses.get(key)
        if status is not None and status.reason != reason:
            status.reason = reason
            self.changed.add(key)

    def collect_keys(self) -> set[tuple[VehicleKey, str]]:
        """The (vehicle, map) whose status changed since the last call."""
        changed, self.changed = self.changed, set()
        return changed
