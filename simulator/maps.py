"""Maps and 3.0 zone sets stored on a simulated vehicle (REFERENCE K.47, L.48).

2.1/3.0 map distribution: ``downloadMap`` pulls the file over HTTP(S) from ``mapDownloadLink``
(checked against ``mapHash``, a SHA-256 hex digest, when given) and stores the version
DISABLED; a version already stored fails (3.0 DUPLICATE_MAP: delete it first). ``enableMap``
enables one version and disables the map's others; ``deleteMap`` removes a DISABLED version
(the enabled one is refused). 3.0 zone sets arrive on the ``zoneSet`` topic, are stored DISABLED
(a zoneSetId already stored is DUPLICATE_ZONE_SET) and ``enableZoneSet`` enables one per map.
Standard library only: the simulator stays framework-free.
"""

from __future__ import annotations

import hashlib
import logging
import urllib.request
from dataclasses import dataclass, field
from urllib.parse import urlparse

from vda5050 import MapState, ParameterValue, v3
from vda5050.enums import MapStatus

log = logging.getLogger(__name__)

MAP_ACTIONS = frozenset({"downloadMap", "enableMap", "deleteMap", "enableZoneSet"})
DOWNLOAD_TIMEOUT = 5.0  # s
MAX_MAP_BYTES = 64 * 1024 * 1024


@dataclass
class StoredZoneSet:
    """A zone set as the vehicle holds it."""

    definition: v3.ZoneSetDefinition
    status: str = "DISABLED"


@dataclass
class MapStore:
    """The maps (versions) and zone sets a vehicle holds."""

    maps: dict[tuple[str, str], str] = field(default_factory=dict)  # (id, version) -> status
    files: dict[tuple[str, str], bytes] = field(default_factory=dict)
    zone_sets: dict[str, StoredZoneSet] = field(default_factory=dict)
    errors: list[tuple[str, str]] = field(default_factory=list)  # (3.0 errorType, text)

    @classmethod
    def booted(cls, map_id: str, version: str) -> MapStore:
        """The store of a vehicle that ships with `version` of `map_id` enabled."""
        return cls(maps={(map_id, version): "ENABLED"})

    def map_ids(self) -> frozenset[str]:
        return frozenset(m for m, _ in self.maps)

    def states(self) -> list[MapState]:
        """``state.maps``."""
        return [
            MapState(map_id=m, map_version=v, map_status=MapStatus(s))
            for (m, v), s in sorted(self.maps.items())
        ]

    def zone_set_states(self) -> list[v3.ZoneSetState]:
        """3.0 ``state.zoneSets``."""
        return [
            v3.ZoneSetState(
                zone_set_id=zone_set_id,
                map_id=stored.definition.map_id,
                zone_set_status=v3.ZoneSetStatus(stored.status),
            )
            for zone_set_id, stored in sorted(self.zone_sets.items())
        ]

    def enabled_zone_sets(self) -> list[v3.ZoneSetDefinition]:
        return [z.definition for z in self.zone_sets.values() if z.status == "ENABLED"]

    # Actions -------------------------------------------------------------------------------

    def apply(self, kind: str, params: dict[str, ParameterValue]) -> str | None:
        """Carry out a map action; the failure reason, or None."""
        if kind == "enableZoneSet":
            return self.enable_zone_set(str(params.get("zoneSetId", "")))
        map_id, version = str(params.get("mapId", "")), str(params.get("mapVersion", ""))
        if not map_id or not version:
            return f"{kind} needs mapId and mapVersion"
        if kind == "downloadMap":
            link, digest = params.get("mapDownloadLink"), params.get("mapHash")
            expected = None if digest is None else str(digest)
            return self.download(map_id, version, str(link or ""), expected)
        if (map_id, version) not in self.maps:
            return f"map {map_id} version {version} is not stored"
        if kind == "enableMap":
            for key in self.maps:
                if key[0] == map_id:
                    self.maps[key] = "DISABLED"
            self.maps[(map_id, version)] = "ENABLED"
            return None
        if self.maps[(map_id, version)] == "ENABLED":
            return f"map {map_id} version {version} is enabled; enable another version first"
        del self.maps[(map_id, version)]
        self.files.pop((map_id, version), None)
        return None

    def download(self, map_id: str, version: str, link: str, digest: str | None) -> str | None:
        if (map_id, version) in self.maps:
            self.errors.append(("DUPLICATE_MAP", f"map {map_id} version {version} is stored"))
            return f"map {map_id} version {version} is already stored (delete it first)"
        if urlparse(link).scheme not in {"http", "https"}:
            return f"mapDownloadLink must be an http(s) URL, got {link!r}"
        try:
            with urllib.request.urlopen(link, timeout=DOWNLOAD_TIMEOUT) as response:  # noqa: S310
                content = response.read(MAX_MAP_BYTES + 1)
        except OSError as exc:
            return f"download of {link} failed: {exc}"
        if len(content) > MAX_MAP_BYTES:
            return "the map file is too large"
        if digest and hashlib.sha256(content).hexdigest() != digest.lower():
            return "the map file does not match mapHash"
        self.maps[(map_id, version)] = "DISABLED"
        self.files[(map_id, version)] = content
        log.info("downloaded map %s version %s (%d bytes)", map_id, version, len(content))
        return None

    def receive_zone_set(self, definition: v3.ZoneSetDefinition) -> str | None:
        """A zone set from the ``zoneSet`` topic; the failure reason, or None."""
        if definition.zone_set_id in self.zone_sets:
            text = f"zone set {definition.zone_set_id} is stored already"
            self.errors.append(("DUPLICATE_ZONE_SET", text))
            return text
        self.zone_sets[definition.zone_set_id] = StoredZoneSet(definition)
        return None

    def enable_zone_set(self, zone_set_id: str) -> str | None:
        stored = self.zone_sets.get(zone_set_id)
        if stored is None:
            return f"zone set {zone_set_id} is not stored"
        for other in self.zone_sets.values():
            if other.definition.map_id == stored.definition.map_id:
                other.status = "DISABLED"
        stored.status = "ENABLED"
        return None


@dataclass
class ZoneRequest:
    """A zone access request the vehicle keeps in its 3.0 state until it left the zone."""

    request_id: str
    zone_set_id: str
    zone_id: str
    status: str = "REQUESTED"

    def key(self) -> tuple[str, str]:
        return (self.zone_set_id, self.zone_id)


@dataclass
class ZoneRequests:
    """3.0 RELEASE zones (REFERENCE L.49-50): the vehicle asks before it enters and waits.

    Before driving towards a node inside an enabled RELEASE zone the vehicle lists an ACCESS
    request (REQUESTED) and stands still until fleet control answers GRANTED on `responses`
    (QUEUED keeps it waiting, REVOKED stops it again). Once neither the vehicle nor its next
    node is inside the zone the request is dropped (the vehicle left). Leases are not tracked:
    a grant lasts until the vehicle leaves (fleet control extends it while it is listed).
    """

    requests: dict[str, ZoneRequest] = field(default_factory=dict)
    counter: int = 0

    def may_drive(
        self, store: MapStore, position: tuple[float, float], target: tuple[float, float]
    ) -> tuple[bool, bool]:
        """(may drive towards `target`, the listed requests changed)."""
        zones = [
            (zone_set.zone_set_id, zone)
            for zone_set in store.enabled_zone_sets()
            for zone in zone_set.zones
            if zone.zone_type == v3.ZoneType.RELEASE
        ]
        changed = False
        for request_id, request in list(self.requests.items()):
            zone = next((z for s, z in zones if (s, z.zone_id) == request.key()), None)
            if zone is None or not (_inside(position, zone) or _inside(target, zone)):
                del self.requests[request_id]  # left the zone (or it is gone)
                changed = True
        allowed = True
        for zone_set_id, zone in zones:
            if not _inside(target, zone):
                continue
            found = [r for r in self.requests.values() if r.key() == (zone_set_id, zone.zone_id)]
            if not found:
                self.counter += 1
                found = [ZoneRequest(f"zr-{self.counter}", zone_set_id, zone.zone_id)]
                self.requests[found[0].request_id] = found[0]
                changed = True
            allowed = allowed and found[0].status == "GRANTED"
        return allowed, changed

    def on_responses(self, responses: list[v3.Response]) -> bool:
        """Take fleet control's answers; True if a request changed."""
        changed = False
        for response in responses:
            request = self.requests.get(response.request_id)
            if request is None:
                continue
            # QUEUED and REJECTED keep the vehicle waiting (REQUESTED).
            status = {"GRANTED": "GRANTED", "REVOKED": "REVOKED"}.get(
                str(response.grant_type), request.status
            )
            if status != request.status:
                request.status = status
                changed = True
        return changed

    def states(self) -> list[v3.ZoneRequest]:
        """3.0 ``state.zoneRequests``."""
        return [
            v3.ZoneRequest(
                request_id=r.request_id,
                request_type=v3.ZoneRequestType.ACCESS,
                zone_id=r.zone_id,
                zone_set_id=r.zone_set_id,
                request_status=v3.RequestStatus(r.status),
            )
            for r in self.requests.values()
        ]


def _inside(point: tuple[float, float], zone: v3.Zone) -> bool:
    """Ray casting: is `point` inside the zone's polygon (on the edge counts as inside)?"""
    x, y = point
    vertices = [(v.x, v.y) for v in zone.vertices]
    inside = False
    for (x1, y1), (x2, y2) in zip(vertices, vertices[1:] + vertices[:1], strict=True):
        if (
            min(x1, x2) - 1e-9 <= x <= max(x1, x2) + 1e-9
            and min(y1, y2) - 1e-9 <= y <= max(y1, y2) + 1e-9
            and abs((x2 - x1) * (y - y1) - (y2 - y1) * (x - x1)) < 1e-9
        ):
            return True  # on an edge
        if (y1 > y) != (y2 > y) and x < (x2 - x1) * (y - y1) / (y2 - y1) + x1:
            inside = not inside
    return inside
