"""A 3.0 fleet against the real Mosquitto on 127.0.0.1:1883, on its own interface name."""

from __future__ import annotations

import json

from simulator import FleetConfig, Layout, SimulatedFleet
from tests.simulator.builders import LAYOUT_DICT, action, instant3, make_order3
from tests.simulator.recorder import Received, Recorder, connection, needs_broker
from tests.simulator.test_v3_schemas import _assert_valid
from vda5050 import TopicKind, encode

pytestmark = needs_broker


def _state_of(serial: str, check: object) -> object:
    def match(m: Received) -> bool:
        return m.kind == "state" and m.serial == serial and bool(check(m.data))  # type: ignore[operator]

    return match


def test_3_0_fleet_end_to_end(recorder3: Recorder) -> None:
    recorder = recorder3
    config = FleetConfig(
        count=2,
        interface=recorder.interface,
        version="3.0.0",
        time_scale=10.0,
        visualization_hz=5.0,
    )
    fleet = SimulatedFleet(Layout.from_dict(LAYOUT_DICT), config)
    fleet.start()
    try:
        assert fleet.wait_connected(10.0)
        recorder.subscribe()  # factsheet and ONLINE come retained, on .../v3/...
        for serial in ("AGV-1", "AGV-2"):
            online = recorder.wait_for(connection(serial, "ONLINE"))
            assert online.retain
            assert online.topic.split("/")[1] == "v3"
            sheet = recorder.wait_for(lambda m, s=serial: m.serial == s and m.kind == "factsheet")
            assert sheet.retain
            assert "mobileRobotActions" in sheet.data["protocolFeatures"]
        visual = recorder.wait_for(lambda m: m.serial == "AGV-2" and m.kind == "visualization")
        assert "referenceStateHeaderId" in visual.data

        pick = action("pick", "p1", loadId="L7", loadType="EPAL")
        order = make_order3("o-int", ["n1", "n2", "n3"], actions={"n2": [pick]})
        recorder.publish("AGV-1", "order", encode(order))
        first = recorder.wait_for(_state_of("AGV-1", lambda d: d["orderId"] == "o-int"))  # type: ignore[arg-type]
        assert "n1" not in [n["nodeId"] for n in first.data["nodeStates"]]
        done = recorder.wait_for(
            _state_of(  # type: ignore[arg-type]
                "AGV-1",
                lambda d: (
                    d["orderId"] == "o-int" and d["nodeStates"] == [] and d["lastNodeId"] == "n3"
                ),
            ),
            timeout=15.0,
        )
        assert [a["actionStatus"] for a in done.data["actionStates"]] == ["FINISHED"]
        assert done.data["mobileRobotPosition"]["x"] == 10.0
        assert done.data["powerSupply"]["stateOfCharge"] < 100.0

        # A 2.x-shaped order does not decode: VALIDATION_FAILURE. cancelOrder without an
        # order fails with NO_ORDER_TO_CANCEL, in instantActionStates.
        recorder.publish("AGV-2", "order", b'{"orderId": 42}')
        recorder.wait_for(
            _state_of(  # type: ignore[arg-type]
                "AGV-2", lambda d: [e["errorType"] for e in d["errors"]] == ["VALIDATION_FAILURE"]
            )
        )
        recorder.publish("AGV-2", "instantActions", encode(instant3(action("cancelOrder", "c9"))))
        recorder.wait_for(
            _state_of(  # type: ignore[arg-type]
                "AGV-2",
                lambda d: any(
                    a["actionId"] == "c9" and a["actionStatus"] == "FAILED"
                    for a in d["instantActionStates"]
                ),
            )
        )
        fleet.break_connection("AGV-2")
        # The last will (3.0 spelling); live delivery carries no retain flag.
        recorder.wait_for(connection("AGV-2", "CONNECTION_BROKEN"), timeout=15.0)
        recorder.wait_for(lambda m: connection("AGV-2", "ONLINE")(m) and not m.retain)
    finally:
        fleet.stop()
    for serial in ("AGV-1", "AGV-2"):
        recorder.wait_for(connection(serial, "OFFLINE"))
    with recorder._cond:
        seen = list(recorder.messages)
    assert all(m.topic.startswith(f"{recorder.interface}/v3/") for m in seen)
    emitted = [m for m in seen if m.kind not in {"order", "instantActions"}]  # not our own
    assert {m.kind for m in emitted} == {"state", "connection", "factsheet", "visualization"}
    for message in emitted:
        _assert_valid(TopicKind(message.kind), json.dumps(message.data).encode())
