"""Instant actions are checked against the factsheet and the operating mode."""

import pytest

import vda5050
from control.capabilities import Capabilities, refuse_instant_action
from vda5050.enums import ActionScope, ValueDataType


def capabilities() -> Capabilities:
    init = vda5050.AgvAction(
        action_type="initPosition",
        action_scopes=[ActionScope.INSTANT, ActionScope.NODE],
        action_parameters=[
            vda5050.ActionParameterSpec(key=k, value_data_type=ValueDataType.NUMBER)
            for k in ("x", "y", "theta")
        ]
        + [
            vda5050.ActionParameterSpec(key="mapId", value_data_type=ValueDataType.STRING),
            vda5050.ActionParameterSpec(
                key="lastNodeId", value_data_type=ValueDataType.STRING, is_optional=True
            ),
        ],
    )
    pick = vda5050.AgvAction(action_type="pick", action_scopes=[ActionScope.NODE])
    return Capabilities({"initPosition": init, "pick": pick})


@pytest.mark.parametrize(
    ("action", "parameters", "reason"),
    [
        ("initPosition", {"x": 1, "y": 2, "theta": 0, "mapId": "m"}, None),
        ("initPosition", {"x": 1, "y": 2}, "initPosition needs parameters mapId, theta"),
        (
            "initPosition",
            {"x": 1, "y": 2, "theta": 0, "mapId": "m", "z": 3},
            "initPosition does not take parameters z",
        ),
        ("pick", {}, "the factsheet declares no instant action pick"),
        ("detectObject", {}, "the factsheet declares no instant action detectObject"),
        ("cancelOrder", {}, None),  # mandatory, declared or not
    ],
)
def test_factsheet_decides_types_scopes_and_parameters(action, parameters, reason) -> None:
    assert refuse_instant_action(capabilities(), "AUTOMATIC", action, parameters) == reason


@pytest.mark.parametrize("mode", ["MANUAL", "SERVICE", "TEACHIN"])
def test_no_actions_in_manual_modes(mode) -> None:
    assert "takes no actions" in refuse_instant_action(capabilities(), mode, "startPause", {})


def test_without_a_factsheet_only_the_safe_defaults_go_out() -> None:
    assert refuse_instant_action(None, "AUTOMATIC", "stateRequest", {}) is None
    assert refuse_instant_action(None, "SEMIAUTOMATIC", "stopPause", {}) is None
    assert "needs a factsheet" in refuse_instant_action(None, "AUTOMATIC", "startCharging", {})
