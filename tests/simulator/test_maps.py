"""The simulator's maps and zones: downloadMap over HTTP, enableMap, deleteMap and state.maps
(2.1/3.0, REFERENCE K.47); 3.0 zone sets and RELEASE-zone access requests (L.48-50)."""

from __future__ import annotations

import hashlib
import http.server
import threading
from collections.abc import Iterator

import pytest

from simulator import wire
from simulator.maps import MapStore
from tests.simulator.builders import action, instant, make_order, make_vehicle, run_until, status
from vda5050 import v3
from vda5050.enums import ActionStatus, BlockingType

FILE = b'{"layouts": []}'


@pytest.fixture
def file_server() -> Iterator[str]:
    """A local HTTP server that serves FILE at /demo-r2.json (and 404 elsewhere)."""

    class Handler(http.server.BaseHTTPRequestHandler):
        def do_GET(self) -> None:  # noqa: N802 - http.server's name
            if self.path != "/demo-r2.json":
                self.send_error(404)
                return
            self.send_response(200)
            self.send_header("Content-Length", str(len(FILE)))
            self.end_headers()
            self.wfile.write(FILE)

        def log_message(self, *args: object) -> None:
            pass

    server = http.server.ThreadingHTTPServer(("127.0.0.1", 0), Handler)
    thread = threading.Thread(target=server.serve_forever, daemon=True)
    thread.start()
    yield f"http://127.0.0.1:{server.server_address[1]}"
    server.shutdown()
    server.server_close()


def map_action(kind: str, action_id: str, **params: str):
    return action(kind, action_id, BlockingType.NONE, **params)


def maps_of(vehicle) -> list[tuple[str, str, str]]:
    (state,) = wire.states(vehicle)
    return [(m.map_id, m.map_version, str(m.map_status)) for m in state.maps or []]


@pytest.mark.parametrize("version", ["2.1.0", "3.0.0"])
def test_download_enable_and_delete_a_map_version(file_server, version) -> None:
    vehicle = make_vehicle(version=version)
    assert maps_of(vehicle) == [("demo", "1", "ENABLED")]
    link = f"{file_server}/demo-r2.json"
    digest = hashlib.sha256(FILE).hexdigest()

    vehicle.on_instant_actions(
        instant(
            map_action(
                "downloadMap",
                "d1",
                mapId="demo",
                mapVersion="r2",
                mapDownloadLink=link,
                mapHash=digest,
            )
        )
    )
    assert status(vehicle, "d1") is ActionStatus.FINISHED
    assert maps_of(vehicle) == [("demo", "1", "ENABLED"), ("demo", "r2", "DISABLED")]
    assert vehicle.map_store.files[("demo", "r2")] == FILE

    vehicle.on_instant_actions(
        instant(map_action("enableMap", "e1", mapId="demo", mapVersion="r2"))
    )
    assert maps_of(vehicle) == [("demo", "1", "DISABLED"), ("demo", "r2", "ENABLED")]

    vehicle.on_instant_actions(
        instant(map_action("deleteMap", "x1", mapId="demo", mapVersion="r2"))
    )
    assert status(vehicle, "x1") is ActionStatus.FAILED  # the enabled one stays
    vehicle.on_instant_actions(instant(map_action("deleteMap", "x2", mapId="demo", mapVersion="1")))
    assert status(vehicle, "x2") is ActionStatus.FINISHED
    assert maps_of(vehicle) == [("demo", "r2", "ENABLED")]


def test_a_bad_download_fails_and_stores_nothing(file_server) -> None:
    store = MapStore.booted("demo", "1")
    assert "does not match mapHash" in store.download(
        "demo", "r2", f"{file_server}/demo-r2.json", "00" * 32
    )
    assert "failed" in store.download("demo", "r3", f"{file_server}/missing.json", None)
    assert "http(s) URL" in store.download("demo", "r4", "file:///etc/passwd", None)
    assert "already stored" in store.download("demo", "1", f"{file_server}/demo-r2.json", None)
    assert store.errors == [("DUPLICATE_MAP", "map demo version 1 is stored")]
    assert set(store.maps) == {("demo", "1")}


def test_a_2_0_vehicle_has_no_map_distribution(file_server) -> None:
    vehicle = make_vehicle(version="2.0.0")
    vehicle.on_instant_actions(
        instant(
            map_action(
                "downloadMap",
                "d1",
                mapId="demo",
                mapVersion="r2",
                mapDownloadLink=f"{file_server}/demo-r2.json",
            )
        )
    )
    assert status(vehicle, "d1") is ActionStatus.FAILED
    (state,) = wire.states(vehicle)
    assert state.maps is None


def _zone_set(zone_set_id: str, *zones: v3.Zone) -> v3.ZoneSetDefinition:
    return v3.ZoneSetDefinition(map_id="demo", zone_set_id=zone_set_id, zones=list(zones))


def _release_zone(x1: float, x2: float) -> v3.Zone:
    return v3.Zone(
        zone_id="Z-REL",
        zone_type=v3.ZoneType.RELEASE,
        vertices=[v3.Vertex(x=x, y=y) for x, y in ((x1, -1), (x2, -1), (x2, 1), (x1, 1))],
        release_loss_behavior=v3.ZoneReleaseLossBehavior.STOP,
    )


def test_a_zone_set_arrives_disabled_and_is_enabled_one_per_map() -> None:
    vehicle = make_vehicle(version="3.0.0")
    store = vehicle.map_store
    assert store.receive_zone_set(_zone_set("ZS-1")) is None
    assert store.receive_zone_set(_zone_set("ZS-2")) is None
    assert "stored already" in store.receive_zone_set(_zone_set("ZS-1"))

    vehicle.on_instant_actions(instant(map_action("enableZoneSet", "z1", zoneSetId="ZS-1")))
    vehicle.on_instant_actions(instant(map_action("enableZoneSet", "z2", zoneSetId="ZS-2")))

    (state,) = wire.states(vehicle)
    assert [(z.zone_set_id, str(z.zone_set_status)) for z in state.zone_sets] == [
        ("ZS-1", "DISABLED"),
        ("ZS-2", "ENABLED"),
    ]


def test_the_vehicle_waits_at_a_release_zone_until_access_is_granted_and_drops_it_after() -> None:
    vehicle = make_vehicle(version="3.0.0", speed=5.0)
    vehicle.map_store.receive_zone_set(_zone_set("ZS", _release_zone(4.0, 6.0)))  # around n2
    vehicle.map_store.enable_zone_set("ZS")
    vehicle.on_order(make_order("O-1", ["n1", "n2", "n3"]))

    run_until(vehicle, lambda v: bool(v.zone_requests.requests), 5)
    vehicle.tick(1.0)
    assert vehicle.last_node_id == "n1"
    assert (vehicle.x, vehicle.y) == (0.0, 0.0)  # waits before the zone
    (state,) = wire.states(vehicle)
    (request,) = state.zone_requests
    assert (request.zone_id, request.zone_set_id, str(request.request_status)) == (
        "Z-REL",
        "ZS",
        "REQUESTED",
    )

    queued = v3.Response(request_id=request.request_id, grant_type=v3.GrantType.QUEUED)
    vehicle.zone_requests.on_responses([queued])
    vehicle.tick(1.0)
    assert vehicle.last_node_id == "n1"

    granted = v3.Response(request_id=request.request_id, grant_type=v3.GrantType.GRANTED)
    assert vehicle.zone_requests.on_responses([granted])
    run_until(vehicle, lambda v: v.last_node_id == "n3", 10)
    (state,) = wire.states(vehicle)
    assert state.zone_requests == []  # left the zone
