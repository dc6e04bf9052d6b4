"""Builders for the map-distribution and zone tests: states with maps, zone sets and requests,
and factsheets as the simulator sends them."""

from typing import Any

import msgspec

from control.controller import Controller
from control.map_sync import MapTarget
from control.zone_sets import build_zone_set
from simulator import wire
from simulator.vehicle import StartPose, VehicleConfig, VirtualVehicle
from tests.control import fakes
from vda5050 import encode

TARGET = MapTarget(
    "demo", "r2", "http://fleet.example/layouts/releases/t/demo-r2.lif.json", "ab" * 32
)
SQUARE = [{"x": 0.0, "y": -1.0}, {"x": 2.0, "y": -1.0}, {"x": 2.0, "y": 1.0}, {"x": 0.0, "y": 1.0}]
ZONES = [
    {"id": "Z-REL", "type": "RELEASE", "vertices": SQUARE, "releaseLossBehavior": "STOP"},
    {"id": "Z-SLOW", "type": "SPEED_LIMIT", "vertices": SQUARE, "maxSpeed": 0.5},
    {"id": "Z-PEN", "type": "PENALTY", "vertices": SQUARE, "penaltyFactor": 0.5},
    {"id": "Z-PARK", "type": "PARKING", "vertices": SQUARE},
]


def factsheet(serial: str = "AGV-1") -> bytes:
    """The simulator's factsheet in the current test version (declares the map actions)."""
    config = VehicleConfig(version=fakes.PROTOCOL["version"], serial_number=serial)
    vehicle = VirtualVehicle(config, StartPose("demo", "a", 0.0, 0.0))
    return encode(wire.factsheet(vehicle))


def state(
    *,
    header_id: int,
    maps: list[tuple[str, str, str]] | None = None,
    zone_sets: list[tuple[str, str]] | None = None,
    zone_requests: list[tuple[str, str, str, str]] = (),  # type: ignore[assignment]
    edge_requests: list[tuple[str, str, str]] = (),  # type: ignore[assignment]
    **kwargs: Any,
) -> bytes:
    """`fakes.state` plus `maps` (mapId, version, status) from 2.1 on, and in 3.0 `zoneSets`
    (zoneSetId, status), `zoneRequests` (requestId, zoneSetId, zoneId, status) and
    `edgeRequests` (requestId, edgeId, status)."""
    data = msgspec.json.decode(fakes.state(header_id=header_id, **kwargs))
    version = fakes.PROTOCOL["version"]
    if maps is not None and version != "2.0.0":
        key = "mapDescriptor" if version.startswith("3.") else "mapDescription"
        data["maps"] = [
            {"mapId": m, "mapVersion": v, "mapStatus": s, key: "test"} for m, v, s in maps
        ]
    if version.startswith("3."):
        if zone_sets is not None:
            data["zoneSets"] = [
                {"zoneSetId": z, "mapId": "demo", "zoneSetStatus": s} for z, s in zone_sets
            ]
        data["zoneRequests"] = [
            {
                "requestId": r,
                "requestType": "ACCESS",
                "zoneSetId": zs,
                "zoneId": z,
                "requestStatus": s,
            }
            for r, zs, z, s in zone_requests
        ]
        data["edgeRequests"] = [
            {
                "requestId": r,
                "requestType": "CORRIDOR",
                "edgeId": e,
                "sequenceId": 1,
                "requestStatus": s,
            }
            for r, e, s in edge_requests
        ]
    return msgspec.json.encode(data)


def online(controller: Controller, serial: str = "AGV-1", **state_args: Any) -> None:
    """The vehicle sends its factsheet and a first state."""
    controller.handle_message(fakes.topic(serial, "factsheet"), factsheet(serial))
    controller.handle_message(fakes.topic(serial), state(header_id=1, serial=serial, **state_args))


def zone_sets() -> dict:
    return {"demo": build_zone_set("demo", ZONES)}


def actions(sent: list[tuple[str, dict]]) -> list[tuple[str, dict[str, Any], str]]:
    """(actionType, parameters, actionId) of every instant action sent."""
    return [
        (
            a["actionType"],
            {p["key"]: p["value"] for p in a.get("actionParameters", [])},
            a["actionId"],
        )
        for topic, message in sent
        if topic.endswith("/instantActions")
        for a in message["actions"]
    ]


def on_topic(sent: list[tuple[str, dict]], kind: str) -> list[dict]:
    return [message for topic, message in sent if topic.endswith(f"/{kind}")]
