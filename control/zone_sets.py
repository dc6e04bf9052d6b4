"""3.0 zone sets (REFERENCE L.48): the layout's zones published on the `zoneSet` topic.

A zone set is built per map from its enabled zones of VDA 5050 types (our own types RESTRICTED,
NO_STOPPING, PARKING and CHARGING have no 3.0 counterpart and stay with routing). A vehicle gets
only the types its factsheet lists in `typeSpecification.supportedZones`, and none if the list is
empty or missing. `zoneSetId` is derived from the content, so a zone set is immutable per id as
the spec asks: any change gives a new id. Sent when the vehicle (re)connects or has no such set
yet, and when the zones change; a vehicle that lists the set DISABLED gets `enableZoneSet` (one
per map: enabling disables the map's others on the vehicle), if its factsheet declares it.
Resent after `RESEND_AFTER` seconds without the vehicle listing it.
"""

import hashlib
import logging
import time
from collections.abc import Callable, Iterable
from dataclasses import dataclass
from typing import Any

import msgspec

from control.live import InstantActionTrack, LiveVehicle, VehicleKey
from vda5050 import v3

logger = logging.getLogger(__name__)

SendAction = Callable[[LiveVehicle, str, dict[str, Any]], InstantActionTrack]
PublishZoneSet = Callable[[LiveVehicle, v3.ZoneSetDefinition], None]
_VDA_TYPES = frozenset(v3.ZoneType)


def build_zone_set(map_id: str, zones: Iterable[dict[str, Any]]) -> v3.ZoneSetDefinition:
    """A 3.0 zone set of `zones` (as `maps.selectors.zone_as_dict` gives them); zones of our own
    types or with unusable data are left out (validation reports them)."""
    built = []
    for zone in zones:
        if not zone.get("enabled", True) or zone.get("type") not in _VDA_TYPES:
            continue
        try:
            built.append(_zone(zone))
        except (msgspec.ValidationError, KeyError, TypeError, ValueError):
            logger.warning("zone %s of map %s left out of the zone set", zone.get("id"), map_id)
    return _with_id(map_id, built)


def only_types(zone_set: v3.ZoneSetDefinition, types: frozenset[str]) -> v3.ZoneSetDefinition:
    """The zone set with only `types` (a vehicle's supportedZones), under its own id."""
    return _with_id(zone_set.map_id, [z for z in zone_set.zones if str(z.zone_type) in types])


def _with_id(map_id: str, zones: list[v3.Zone]) -> v3.ZoneSetDefinition:
    digest = hashlib.sha256(msgspec.json.encode(zones)).hexdigest()[:16]
    return v3.ZoneSetDefinition(map_id=map_id, zone_set_id=f"{map_id}.{digest}", zones=zones)


def _zone(zone: dict[str, Any]) -> v3.Zone:
    kind = zone["type"]
    data: dict[str, Any] = {
        "zoneId": zone["id"],
        "zoneType": kind,
        "vertices": [{"x": float(v["x"]), "y": float(v["y"])} for v in zone["vertices"]],
    }
    if zone.get("name"):
        data["zoneDescriptor"] = zone["name"]
    if kind == "SPEED_LIMIT":
        data["maximumSpeed"] = zone["maxSpeed"]
    elif kind == "RELEASE":
        data["releaseLossBehavior"] = zone.get("releaseLossBehavior") or "STOP"
    elif kind == "ACTION":
        for key in ("entryActions", "duringActions", "exitActions"):
            data[key] = zone.get(key) or []
    elif kind == "PRIORITY":
        data["priorityFactor"] = zone["priorityFactor"]
    elif kind == "PENALTY":
        data["penaltyFactor"] = zone["penaltyFactor"]
    elif kind == "DIRECTED":
        data |= {"direction": zone["direction"], "directedLimitation": zone["limitation"]}
    elif kind == "BIDIRECTED":
        data |= {"direction": zone["direction"], "bidirectedLimitation": zone["limitation"]}
    return msgspec.convert(data, v3.Zone)


@dataclass
class _Sent:
    zone_set_id: str
    at: float
    enable_track: InstantActionTrack | None = None
    enable_at: float = float("-inf")


class ZoneSetSync:
    """Publishes each 3.0 vehicle its maps' zone sets and enables them (L.48)."""

    RESEND_AFTER = 30.0

    def __init__(self, publish: PublishZoneSet, send: SendAction) -> None:
        self.publish, self.send = publish, send
        self.zone_sets: dict[str, v3.ZoneSetDefinition] = {}
        self.supported: dict[VehicleKey, frozenset[str]] = {}
        self.can_enable: dict[VehicleKey, bool] = {}
        self.reported: dict[VehicleKey, dict[str, str]] = {}  # zoneSetId -> zoneSetStatus
        self.sent: dict[tuple[VehicleKey, str], _Sent] = {}
        # Filtered sets by (map, supported types): hashing a set per state would cost too much.
        self._filtered: dict[tuple[str, frozenset[str]], v3.ZoneSetDefinition] = {}
        self._steady: dict[VehicleKey, tuple[object, ...]] = {}
        self._generation = 0  # counts zone-set changes

    def set_zone_sets(
        self, zone_sets: dict[str, v3.ZoneSetDefinition], vehicles: Iterable[LiveVehicle]
    ) -> None:
        """Take the layouts' zone sets; a change goes out to the vehicles at once."""
        if zone_sets == self.zone_sets:
            return
        self.zone_sets = dict(zone_sets)
        self._filtered = {}
        self._generation += 1
        for vehicle in vehicles:
            self.step(vehicle)

    def on_factsheet(self, vehicle: LiveVehicle, factsheet: v3.Factsheet) -> None:
        zones = factsheet.type_specification.supported_zones or []
        self.supported[vehicle.key] = frozenset(str(z) for z in zones)
        self.can_enable[vehicle.key] = any(
            a.action_type == "enableZoneSet"
            for a in factsheet.protocol_features.mobile_robot_actions
        )
        self.step(vehicle)

    def on_state(self, vehicle: LiveVehicle, state: v3.State) -> None:
        if not self.supported.get(vehicle.key):
            return  # no zones for this vehicle (hot path)
        position = state.mobile_robot_position
        seen = (
            tuple(state.zone_sets or ()),
            tuple(state.maps or ()),
            position.map_id if position is not None else None,
            self._generation,
        )
        if self._steady.get(vehicle.key) == seen:
            return  # every wanted zone set is ENABLED and nothing changed (hot path)
        self.reported[vehicle.key] = {
            z.zone_set_id: str(z.zone_set_status) for z in state.zone_sets or []
        }
        if self.step(vehicle):
            self._steady[vehicle.key] = seen
        else:
            self._steady.pop(vehicle.key, None)

    def forget(self, vehicle: LiveVehicle) -> None:
        """The vehicle (re)connected: what we sent before may be gone, send again."""
        for key in [k for k in self.sent if k[0] == vehicle.key]:
            del self.sent[key]
        self._steady.pop(vehicle.key, None)

    def wanted(self, vehicle: LiveVehicle) -> list[v3.ZoneSetDefinition]:
        """The zone sets this vehicle should hold: of the map it stands on and those it lists."""
        types = self.supported.get(vehicle.key)
        state = vehicle.state
        if not types or state is None or not vehicle.version.startswith("3."):
            return []
        maps = {m.map_id for m in state.maps or []}
        if state.agv_position is not None:
            maps.add(state.agv_position.map_id)
        wanted = []
        for map_id in sorted(maps & self.zone_sets.keys()):
            key = (map_id, types)
            if key not in self._filtered:
                self._filtered[key] = only_types(self.zone_sets[map_id], types)
            wanted.append(self._filtered[key])
        return wanted

    def step(self, vehicle: LiveVehicle, now: float | None = None) -> bool:
        """Send what the vehicle lacks; True if it has every wanted zone set ENABLED."""
        now = time.monotonic() if now is None else now
        listed = self.reported.get(vehicle.key, {})
        steady = True
        for zone_set in self.wanted(vehicle):
            key = (vehicle.key, zone_set.map_id)
            sent = self.sent.get(key)
            status = listed.get(zone_set.zone_set_id)
            steady = steady and status == "ENABLED"
            if status is None:
                if (
                    sent is None
                    or sent.zone_set_id != zone_set.zone_set_id
                    or (now - sent.at >= self.RESEND_AFTER)
                ):
                    self.publish(vehicle, zone_set)
                    self.sent[key] = _Sent(zone_set.zone_set_id, now)
                continue
            if sent is None or sent.zone_set_id != zone_set.zone_set_id:
                sent = self.sent[key] = _Sent(zone_set.zone_set_id, now)  # e.g. after a restart
            enable = status == "DISABLED" and self.can_enable.get(vehicle.key)
            if enable and now - sent.enable_at >= self.RESEND_AFTER:
                sent.enable_track = self.send(
                    vehicle, "enableZoneSet", {"zoneSetId": zone_set.zone_set_id}
                )
                sent.enable_at = now
        return steady

    def status(self, vehicle: LiveVehicle, map_id: str) -> tuple[str, str]:
        """(zoneSetId, SENT | DISABLED | ENABLED) of the vehicle's zone set of `map_id`."""
        sent = self.sent.get((vehicle.key, map_id))
        if sent is None:
            return "", ""
        return sent.zone_set_id, self.reported.get(vehicle.key, {}).get(sent.zone_set_id, "SENT")
