"""The vehicle page: rendered from the snapshot, buttons by permission through the audited
vehicle-command services, and its websocket asking control to watch the vehicle."""

import json
from typing import Any

import pytest
from asgiref.sync import async_to_sync
from channels.layers import get_channel_layer
from channels.routing import URLRouter
from channels.testing import WebsocketCommunicator
from django.contrib.auth import get_user_model
from django.contrib.auth.models import Permission

from control.vehicle_consumers import NOT_PERMITTED
from fleet import roles
from fleet.control_queue import receive_commands
from fleet.models import AuditEntry
from fleet.realtime import vehicle_group
from fleet.routing import websocket_urlpatterns
from orders.models import VehicleCommand
from robots.models import Vehicle
from tests.factories import VehicleFactory, user_with_role

pytestmark = pytest.mark.django_db


def _url(vehicle: Vehicle, suffix: str = "") -> str:
    return f"/vehicles/{vehicle.manufacturer}/{vehicle.serial_number}/{suffix}"


def _post(client: Any, vehicle: Vehicle, **body: Any) -> Any:
    return client.post(_url(vehicle, "command/"), json.dumps(body), content_type="application/json")


def test_the_page_shows_the_snapshot_before_any_live_message(client: Any) -> None:
    vehicle = VehicleFactory(
        serial_number="AGV-7", order_id="TO-3", last_node_id="A2.1", paused=True, x=3.5, y=6.0
    )
    client.force_login(user_with_role(roles.OPERATOR))

    response = client.get(_url(vehicle))

    assert response.status_code == 200
    html = response.content.decode()
    assert 'id="s-order">TO-3<' in html
    assert 'id="s-paused">yes<' in html
    assert f'data-socket="/ws/vehicles/{vehicle.pk}/"' in html
    snapshot = response.context["snapshot"]
    assert (snapshot["x"], snapshot["y"], snapshot["last_node"]) == (3.5, 6.0, "A2.1")
    assert 'data-action="pause">' in html  # enabled for an operator
    assert response.context["allowed"] == sorted(
        ["pause", "resume", "cancel_order", "init_position", "state_request"]
        + ["factsheet_request", "charge", "park"]
    )


def test_a_manager_sees_the_page_but_may_not_command(client: Any) -> None:
    vehicle = VehicleFactory()
    client.force_login(user_with_role(roles.MANAGER))

    page = client.get(_url(vehicle))
    refused = _post(client, vehicle, action="pause")

    assert page.status_code == 200
    assert page.context["allowed"] == []
    assert 'data-action="pause" disabled' in page.content.decode()
    assert refused.status_code == 403
    assert not VehicleCommand.objects.exists()


def test_people_without_view_operations_are_refused(client: Any) -> None:
    vehicle = VehicleFactory()
    client.force_login(get_user_model().objects.create_user("visitor"))

    assert client.get(_url(vehicle)).status_code == 403
    assert _post(client, vehicle, action="pause").status_code == 403


def test_pause_goes_through_the_audited_command_service(client: Any) -> None:
    vehicle = VehicleFactory()
    user = user_with_role(roles.OPERATOR)
    client.force_login(user)

    response = _post(client, vehicle, action="pause")

    assert response.status_code == 202
    command = VehicleCommand.objects.get()
    assert response.json()["command"] == {
        "id": command.pk,
        "kind": "vehicle.pause",
        "status": "QUEUED",
    }
    assert (command.vehicle, command.requested_by) == (vehicle, user)
    entry = AuditEntry.objects.get(action="vehicle.command")
    assert entry.detail["kind"] == "vehicle.pause"


def test_init_position_sends_the_clicked_pose(client: Any) -> None:
    vehicle = VehicleFactory(map_id="demo")
    client.force_login(user_with_role(roles.TECHNICIAN))

    response = _post(
        client, vehicle, action="init_position", x=3, y=6.5, theta=1.57, lastNodeId="A1.2"
    )

    assert response.status_code == 202
    command = VehicleCommand.objects.get()
    assert command.parameters == {
        "action_type": "initPosition",
        "parameters": {"x": 3.0, "y": 6.5, "theta": 1.57, "mapId": "demo", "lastNodeId": "A1.2"},
    }
    bad = _post(client, vehicle, action="init_position", x="left", y=1, theta=0)
    assert bad.status_code == 409


def test_refusals_come_back_with_the_reason(client: Any) -> None:
    vehicle = VehicleFactory()
    offline = VehicleFactory(connection=Vehicle.Connection.OFFLINE)
    client.force_login(user_with_role(roles.OPERATOR))

    no_order = _post(client, vehicle, action="cancel_order")
    not_connected = _post(client, offline, action="resume")
    unknown = _post(client, vehicle, action="selfDestruct")

    assert no_order.status_code == 409
    assert "no transport order" in no_order.json()["detail"]
    assert not_connected.status_code == 409
    assert "OFFLINE" in not_connected.json()["detail"]
    assert unknown.status_code == 400


def test_charge_and_park_need_their_own_permission(client: Any) -> None:
    vehicle = VehicleFactory()
    user = get_user_model().objects.create_user("pauser")
    roles.sync_roles()
    for codename in ("view_operations", "command_vehicles"):
        user.user_permissions.add(
            Permission.objects.get(content_type__app_label="fleet", codename=codename)
        )
    client.force_login(user)

    page = client.get(_url(vehicle))

    assert "charge" not in page.context["allowed"]
    assert "pause" in page.context["allowed"]
    assert _post(client, vehicle, action="charge").status_code == 403
    assert _post(client, vehicle, action="park").status_code == 403


def _websocket(user: Any, pk: int, send_event: bool) -> tuple[bool, Any, Any]:
    async def scenario() -> tuple[bool, Any, Any]:
        communicator = WebsocketCommunicator(
            URLRouter(websocket_urlpatterns), f"/ws/vehicles/{pk}/"
        )
        communicator.scope["user"] = user
        connected, code = await communicator.connect()
        received = None
        if connected and send_event:
            await communicator.send_json_to({"type": "watch"})  # too soon: not forwarded
            await get_channel_layer().group_send(
                vehicle_group(pk),
                {"type": "fleet.event", "event": "vehicle.messages", "payload": {"messages": []}},
            )
            received = await communicator.receive_json_from(timeout=5)
            await communicator.disconnect()
        return connected, code, received

    return async_to_sync(scenario)()


def test_the_websocket_asks_control_to_watch_and_forwards_its_messages(settings: Any) -> None:
    settings.REDIS_URL = ""  # the in-process command queue, read back below
    receive_commands(0.01)  # drop leftovers of other tests
    user = user_with_role(roles.MANAGER)

    connected, _, received = _websocket(user, 42, send_event=True)

    assert connected
    assert received == {"event": "vehicle.messages", "payload": {"messages": []}}
    watches = [c for c in receive_commands(0.5) if c["kind"] == "vehicle.watch"]
    assert watches == [{"kind": "vehicle.watch", "vehicle": 42, "seconds": 30.0, "full": True}]


def test_the_websocket_refuses_people_without_view_operations() -> None:
    user = get_user_model().objects.create_user("visitor")
    assert _websocket(user, 42, send_event=False)[:2] == (False, NOT_PERMITTED)
