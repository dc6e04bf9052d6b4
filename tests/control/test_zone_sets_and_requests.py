"""3.0 zone sets (REFERENCE L.48) and answers to zone/edge requests (L.49).

Runs for 2.0.0, 2.1.0 and 3.0.0: 2.x vehicles must get neither topic; every published message is
validated against the official schema of its version and topic (fixture `sent`).
"""

import pytest

import vda5050
from control.zone_sets import build_zone_set
from tests.control import test_controller as base
from tests.control.distribution_support import ZONES, actions, on_topic, online, state, zone_sets
from tests.control.fakes import topic

protocol_version = base.protocol_version
sent = base.sent
controller = base.controller


def only_3_0(version: str) -> None:
    if not version.startswith("3."):
        pytest.skip("zone sets and requests exist from 3.0 on")


def test_L48_a_3_0_vehicle_gets_its_maps_zone_set_with_the_zone_types_it_supports(
    controller, sent, protocol_version
) -> None:
    controller.distribution.set_targets({}, zone_sets())
    online(controller)

    published = on_topic(sent, "zoneSet")
    if not protocol_version.startswith("3."):
        assert published == []  # 2.x has no zoneSet topic
        return
    (message,) = published
    zone_set = message["zoneSet"]
    assert zone_set["mapId"] == "demo"
    # The simulator supports BLOCKED, SPEED_LIMIT and RELEASE; PENALTY is left out, and the
    # PARKING zone is ours only (no 3.0 type).
    assert [(z["zoneId"], z["zoneType"]) for z in zone_set["zones"]] == [
        ("Z-REL", "RELEASE"),
        ("Z-SLOW", "SPEED_LIMIT"),
    ]
    assert zone_set["zones"][1]["maximumSpeed"] == 0.5
    assert zone_set["zones"][0]["releaseLossBehavior"] == "STOP"


def test_L48_the_stored_zone_set_is_enabled_and_then_left_alone(
    controller, sent, protocol_version
) -> None:
    only_3_0(protocol_version)
    controller.distribution.set_targets({}, zone_sets())
    online(controller)
    zone_set_id = on_topic(sent, "zoneSet")[0]["zoneSet"]["zoneSetId"]

    controller.handle_message(topic(), state(header_id=2, zone_sets=[(zone_set_id, "DISABLED")]))
    kind, params, _ = actions(sent)[-1]
    assert (kind, params) == ("enableZoneSet", {"zoneSetId": zone_set_id})

    controller.handle_message(topic(), state(header_id=3, zone_sets=[(zone_set_id, "ENABLED")]))
    assert [a[0] for a in actions(sent)].count("enableZoneSet") == 1
    assert len(on_topic(sent, "zoneSet")) == 1
    vehicle = controller.fleet.by_pk(1)
    assert controller.distribution.zone_sets.status(vehicle, "demo") == (zone_set_id, "ENABLED")


def test_L48_changed_zones_go_out_as_a_new_zone_set_and_a_reconnect_sends_it_again(
    controller, sent, protocol_version
) -> None:
    only_3_0(protocol_version)
    controller.distribution.set_targets({}, zone_sets())
    online(controller)
    first = on_topic(sent, "zoneSet")[0]["zoneSet"]["zoneSetId"]

    slower = [dict(z, maxSpeed=0.3) if z["id"] == "Z-SLOW" else z for z in ZONES]
    controller.distribution.set_targets({}, {"demo": build_zone_set("demo", slower)})

    second = on_topic(sent, "zoneSet")[-1]["zoneSet"]
    assert second["zoneSetId"] != first  # immutable per id: new content, new id
    assert second["zones"][1]["maximumSpeed"] == 0.3
    assert build_zone_set("demo", slower).zone_set_id == build_zone_set("demo", slower).zone_set_id

    connection = base.fakes.topic(kind="connection")
    controller.handle_message(connection, _online_connection())
    controller.handle_message(topic(), state(header_id=1))
    assert len(on_topic(sent, "zoneSet")) == 3


def _online_connection() -> bytes:
    message = vda5050.make_connection(
        header_id=7,
        manufacturer="sim",
        serial_number="AGV-1",
        connection_state=vda5050.ConnectionState.ONLINE,
        version=base.fakes.PROTOCOL["version"],
    )
    if base.fakes.PROTOCOL["version"].startswith("3."):
        message = vda5050.adapt.connection_v2_to_v3(message)
    return vda5050.encode(message)


def _responses(sent, serial: str) -> list[dict]:
    return [r for t, m in sent if t.endswith(f"/{serial}/responses") for r in m["responses"]]


def test_L49_a_zone_is_granted_to_one_vehicle_and_queued_for_the_next_until_it_leaves(
    controller, sent, protocol_version
) -> None:
    only_3_0(protocol_version)
    online(controller, "AGV-1")
    online(controller, "AGV-2")
    request = ("REQ-1", "ZS", "Z-REL", "REQUESTED")
    controller.handle_message(topic("AGV-1"), state(header_id=2, zone_requests=[request]))
    controller.handle_message(
        topic("AGV-2"), state(header_id=2, serial="AGV-2", zone_requests=[request])
    )

    (granted,) = _responses(sent, "AGV-1")
    assert granted["grantType"] == "GRANTED"
    assert granted["leaseExpiry"].endswith("Z")
    assert _responses(sent, "AGV-2") == [{"requestId": "REQ-1", "grantType": "QUEUED"}]

    # AGV-1 holds it, states repeat: no new answers.
    held = ("REQ-1", "ZS", "Z-REL", "GRANTED")
    controller.handle_message(topic("AGV-1"), state(header_id=3, zone_requests=[held]))
    assert len(_responses(sent, "AGV-1")) == 1
    # AGV-1 left the zone: its request is gone, AGV-2 is granted at once.
    controller.handle_message(topic("AGV-1"), state(header_id=4))
    assert [r["grantType"] for r in _responses(sent, "AGV-2")] == ["QUEUED", "GRANTED"]


def test_L49_an_untaken_answer_is_resent_and_a_lease_is_extended_before_it_runs_out(
    controller, sent, protocol_version
) -> None:
    only_3_0(protocol_version)
    online(controller)
    arbiter = controller.distribution.requests
    vehicle = controller.fleet.by_pk(1)

    def v3_state(status: str, header: int):
        return vda5050.decode(
            "state",
            state(header_id=header, edge_requests=[("REQ-E", "bc", status)]),
            version="3.0.0",
        )

    arbiter.on_state(vehicle, v3_state("REQUESTED", 2), now=100.0)
    arbiter.on_state(vehicle, v3_state("REQUESTED", 3), now=101.0)  # too soon to resend
    arbiter.on_state(vehicle, v3_state("REQUESTED", 4), now=106.0)  # lost? send again
    assert [r["grantType"] for r in _responses(sent, "AGV-1")] == ["GRANTED", "GRANTED"]
    arbiter.on_state(vehicle, v3_state("GRANTED", 5), now=110.0)  # taken up, lease long
    assert len(_responses(sent, "AGV-1")) == 2
    arbiter.on_state(vehicle, v3_state("GRANTED", 6), now=106.0 + arbiter.LEASE * 0.6)
    assert len(_responses(sent, "AGV-1")) == 3  # extended


def test_L49_a_silent_holder_loses_its_grant_when_the_lease_runs_out(
    controller, sent, protocol_version
) -> None:
    only_3_0(protocol_version)
    online(controller, "AGV-1")
    online(controller, "AGV-2")
    arbiter = controller.distribution.requests
    request = ("REQ-9", "ZS", "Z-REL", "REQUESTED")
    controller.handle_message(topic("AGV-1"), state(header_id=2, zone_requests=[request]))
    controller.handle_message(
        topic("AGV-2"), state(header_id=2, serial="AGV-2", zone_requests=[request])
    )
    arbiter.tick(now=1.0)  # within the lease: nothing changes
    assert [r["grantType"] for r in _responses(sent, "AGV-2")] == ["QUEUED"]

    arbiter.tick(now=1e12)  # AGV-1 never extended it

    assert [r["grantType"] for r in _responses(sent, "AGV-2")] == ["QUEUED", "GRANTED"]


def test_L49_2_x_vehicles_get_no_responses(controller, sent, protocol_version) -> None:
    online(controller)
    controller.handle_message(
        topic(), state(header_id=2, zone_requests=[("R", "Z", "Z", "REQUESTED")])
    )
    if protocol_version.startswith("3."):
        assert len(on_topic(sent, "responses")) == 1
    else:
        assert on_topic(sent, "responses") == []
