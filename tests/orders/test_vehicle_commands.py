"""Commands to vehicles over the API: recorded, queued for control after commit."""

import pytest

from orders.models import TransportOrder, VehicleCommand
from tests.factories import VehicleFactory


@pytest.fixture
def vehicle(demo_map):
    return VehicleFactory(last_node_id="A4.1")  # next to CHARGE-1 (A5.1) and far from parking


def command(api, vehicle, name: str, body: dict | None = None, capture=None):
    with capture(execute=True):
        return api.post(f"/api/v1/vehicles/{vehicle.pk}/{name}/", body or {}, format="json")


def test_pause_and_resume_are_queued_for_control(
    api, vehicle, sent_commands, django_capture_on_commit_callbacks, erp
) -> None:
    paused = command(api, vehicle, "pause", capture=django_capture_on_commit_callbacks)
    resumed = command(api, vehicle, "resume", capture=django_capture_on_commit_callbacks)

    assert paused.status_code == resumed.status_code == 202
    assert paused.json()["kind"] == "vehicle.pause"
    assert [kind for kind, _ in sent_commands] == ["vehicle.pause", "vehicle.resume"]
    assert sent_commands[0][1] == {"vehicle": vehicle.pk, "command": paused.json()["id"]}
    recorded = VehicleCommand.objects.get(pk=paused.json()["id"])
    assert (recorded.vehicle, recorded.requested_by) == (vehicle, erp.user)


def test_charge_goes_to_the_nearest_charger_unless_one_is_named(
    api, vehicle, sent_commands, django_capture_on_commit_callbacks
) -> None:
    nearest = command(api, vehicle, "charge", capture=django_capture_on_commit_callbacks)
    named = command(
        api, vehicle, "charge", {"station": "CHARGE-2"}, capture=django_capture_on_commit_callbacks
    )

    assert nearest.status_code == 202
    assert nearest.json()["parameters"] == {
        "station": "CHARGE-1",
        "node": "S-CHARGE-1",
        "map": "demo",
    }
    assert named.json()["parameters"]["station"] == "CHARGE-2"
    assert sent_commands[0] == (
        "vehicle.charge",
        {
            "vehicle": vehicle.pk,
            "command": nearest.json()["id"],
            "station": "CHARGE-1",
            "node": "S-CHARGE-1",
            "map": "demo",
        },
    )


def test_park_goes_to_the_nearest_parking_station(
    api, demo_map, django_capture_on_commit_callbacks
) -> None:
    vehicle = VehicleFactory(last_node_id="A0.2")

    parked = command(api, vehicle, "park", capture=django_capture_on_commit_callbacks)

    assert parked.status_code == 202
    assert parked.json()["parameters"]["station"] == "PARK-3"


@pytest.mark.parametrize(
    ("body", "status", "text"),
    [
        ({"station": "PARK-1"}, 422, "not a CHARGE station"),
        ({"station": "NOPE"}, 400, "No station"),
    ],
)
def test_charge_to_a_wrong_station_is_refused(api, vehicle, body, status, text) -> None:
    response = api.post(f"/api/v1/vehicles/{vehicle.pk}/charge/", body, format="json")

    assert response.status_code == status
    assert text in str(response.json())
    assert not VehicleCommand.objects.exists()


def test_a_busy_unavailable_or_disconnected_vehicle_is_409(api, vehicle, station) -> None:
    TransportOrder.objects.create(
        source=station("PICK-1"),
        destination=station("DROP-1"),
        vehicle=vehicle,
        status=TransportOrder.Status.IN_PROGRESS,
    )
    manual = VehicleFactory(operating_mode="MANUAL")
    offline = VehicleFactory(connection="OFFLINE")

    busy = api.post(f"/api/v1/vehicles/{vehicle.pk}/park/", {}, format="json")
    unavailable = api.post(f"/api/v1/vehicles/{manual.pk}/charge/", {}, format="json")
    disconnected = api.post(f"/api/v1/vehicles/{offline.pk}/pause/", {}, format="json")

    assert (busy.status_code, unavailable.status_code, disconnected.status_code) == (409, 409, 409)
    assert "cancel it first" in busy.json()["detail"]
    assert "OFFLINE" in disconnected.json()["detail"]
    assert api.post("/api/v1/vehicles/999999/pause/").status_code == 404


def test_instant_actions_are_queued_with_their_parameters(
    api, vehicle, sent_commands, django_capture_on_commit_callbacks
) -> None:
    response = command(
        api,
        vehicle,
        "instant-actions",
        {"action_type": "initPosition", "parameters": {"x": 1.5, "y": 2, "mapId": "demo"}},
        capture=django_capture_on_commit_callbacks,
    )

    assert response.status_code == 202, response.content
    assert sent_commands == [
        (
            "vehicle.instant_action",
            {
                "vehicle": vehicle.pk,
                "command": response.json()["id"],
                "action_type": "initPosition",
                "parameters": {"x": 1.5, "y": 2, "mapId": "demo"},
            },
        )
    ]


@pytest.mark.parametrize(
    ("body", "status"),
    [
        ({"action_type": "cancelOrder"}, 422),
        ({"action_type": "startPause"}, 422),
        ({"action_type": "no spaces"}, 422),
        ({"action_type": "stateRequest", "parameters": [1, 2]}, 400),
        ({"action_type": "stateRequest", "parameters": {"k": "nul\u0000"}}, 400),
        ({"parameters": {}}, 400),
    ],
)
def test_bad_instant_actions_are_refused(api, vehicle, body, status) -> None:
    response = api.post(f"/api/v1/vehicles/{vehicle.pk}/instant-actions/", body, format="json")

    assert response.status_code == status, response.content
    assert not VehicleCommand.objects.exists()


def test_the_factsheet_limits_instant_actions_to_those_offered(api, demo_map) -> None:
    vehicle = VehicleFactory(
        factsheet={
            "protocolFeatures": {
                "agvActions": [
                    {"actionType": "stateRequest", "actionScopes": ["INSTANT"]},
                    {"actionType": "pick", "actionScopes": ["NODE"]},
                ]
            }
        }
    )
    url = f"/api/v1/vehicles/{vehicle.pk}/instant-actions/"

    offered = api.post(url, {"action_type": "stateRequest"}, format="json")
    node_only = api.post(url, {"action_type": "pick"}, format="json")

    assert offered.status_code == 202
    assert node_only.status_code == 422
    assert "does not offer pick" in node_only.json()["detail"]
