"""The vehicle page: one vehicle as the VDA 5050 visualizer shows it, live, with its commands.

The page is rendered from the database snapshot (so it works before the first live message);
its websocket (`control.vehicle_consumers`) then brings the raw messages from `control`.
Buttons post to `vehicle_command`, which goes through the same audited services as the API.
"""

import json
from collections.abc import Callable
from typing import Any

from django.contrib.auth.decorators import login_required, permission_required
from django.http import HttpRequest, HttpResponse, JsonResponse
from django.shortcuts import get_object_or_404, render
from django.views.decorators.http import require_POST

from fleet import roles
from fleet.exceptions import DomainError
from maps.models import Map
from maps.selectors import get_default_map, layout_as_dict
from orders import services
from orders.models import TransportOrder, VehicleCommand
from robots.models import Vehicle

Handler = Callable[[Vehicle, dict[str, Any], Any], Any]


def _init_position(vehicle: Vehicle, data: dict[str, Any], user: Any) -> VehicleCommand:
    try:
        x, y, theta = (float(data[key]) for key in ("x", "y", "theta"))
    except (KeyError, TypeError, ValueError) as exc:
        raise DomainError("initPosition needs numbers x, y and theta") from exc
    parameters = {
        "x": x,
        "y": y,
        "theta": theta,
        "mapId": str(data.get("mapId") or vehicle.map_id),
        "lastNodeId": str(data.get("lastNodeId") or ""),
    }
    return services.request_instant_action(
        vehicle=vehicle, action_type="initPosition", parameters=parameters, by=user
    )


def _cancel_order(vehicle: Vehicle, data: dict[str, Any], user: Any) -> TransportOrder:
    order = TransportOrder.objects.filter(
        vehicle=vehicle, status__in=TransportOrder.ACTIVE_STATUSES
    ).first()
    if order is None:
        raise DomainError(f"{vehicle} has no transport order to cancel")
    return services.cancel_transport_order(
        order=order, reason="cancelled on the vehicle page", by=user
    )


# action -> (permission, handler). Cancel and initPosition are confirmed in the page first.
ACTIONS: dict[str, tuple[str, Handler]] = {
    "pause": (roles.COMMAND_VEHICLES, lambda v, d, u: services.pause_vehicle(vehicle=v, by=u)),
    "resume": (roles.COMMAND_VEHICLES, lambda v, d, u: services.resume_vehicle(vehicle=v, by=u)),
    "cancel_order": (roles.COMMAND_VEHICLES, _cancel_order),
    "init_position": (roles.COMMAND_VEHICLES, _init_position),
    "state_request": (
        roles.COMMAND_VEHICLES,
        lambda v, d, u: services.request_instant_action(
            vehicle=v, action_type="stateRequest", by=u
        ),
    ),
    "factsheet_request": (
        roles.COMMAND_VEHICLES,
        lambda v, d, u: services.request_instant_action(
            vehicle=v, action_type="factsheetRequest", by=u
        ),
    ),
    "charge": (
        roles.SEND_TO_CHARGE_OR_PARK,
        lambda v, d, u: services.send_vehicle_to_charge(vehicle=v, by=u),
    ),
    "park": (
        roles.SEND_TO_CHARGE_OR_PARK,
        lambda v, d, u: services.send_vehicle_to_park(vehicle=v, by=u),
    ),
}


@login_required
@permission_required(roles.VIEW_OPERATIONS, raise_exception=True)
def vehicle_page(request: HttpRequest, manufacturer: str, serial: str) -> HttpResponse:
    """Header, message chips, state summary, order graph, message log and command buttons."""
    vehicle = get_object_or_404(Vehicle, manufacturer=manufacturer, serial_number=serial)
    layout = Map.objects.filter(map_id=vehicle.map_id).first() or get_default_map()
    allowed = {
        action
        for action, (permission, _handler) in ACTIONS.items()
        if request.user.has_perm(permission)
    }
    return render(
        request,
        "control/vehicle.html",
        {
            "vehicle": vehicle,
            "snapshot": _snapshot(vehicle),
            "layout": layout_as_dict(map=layout) if layout else None,
            "allowed": sorted(allowed),
            "commands": vehicle.commands.order_by("-created_at")[:10],
        },
    )


@require_POST
@login_required
@permission_required(roles.VIEW_OPERATIONS, raise_exception=True)
def vehicle_command(request: HttpRequest, manufacturer: str, serial: str) -> JsonResponse:
    """Carry out one button of the page (JSON body `{"action": …, …}`); answers JSON."""
    vehicle = get_object_or_404(Vehicle, manufacturer=manufacturer, serial_number=serial)
    try:
        data = json.loads(request.body or b"{}")
    except ValueError:
        data = None
    if not isinstance(data, dict) or data.get("action") not in ACTIONS:
        return JsonResponse({"detail": "unknown action"}, status=400)
    permission, handler = ACTIONS[data["action"]]
    if not request.user.has_perm(permission):
        return JsonResponse({"detail": "you may not do this"}, status=403)
    try:
        result = handler(vehicle, data, request.user)
    except DomainError as exc:
        return JsonResponse({"detail": str(exc)}, status=exc.http_status)
    if isinstance(result, VehicleCommand):
        return JsonResponse(
            {"command": {"id": result.pk, "kind": result.kind, "status": result.status}},
            status=202,
        )
    return JsonResponse({"order": {"id": result.pk, "status": result.status}}, status=202)


def _snapshot(vehicle: Vehicle) -> dict[str, Any]:
    """The flushed state of the vehicle, in the names the page's script uses."""
    return {
        "id": vehicle.pk,
        "manufacturer": vehicle.manufacturer,
        "serial": vehicle.serial_number,
        "version": vehicle.protocol_version,
        "connection": vehicle.connection,
        "map": vehicle.map_id,
        "x": vehicle.x,
        "y": vehicle.y,
        "theta": vehicle.theta,
        "position_initialized": vehicle.position_initialized,
        "battery": vehicle.battery_charge,
        "charging": vehicle.charging,
        "driving": vehicle.driving,
        "paused": vehicle.paused,
        "mode": vehicle.operating_mode,
        "errors": vehicle.errors or [],
        "loads": vehicle.loads or [],
        "order_id": vehicle.order_id,
        "order_update_id": vehicle.order_update_id,
        "last_node": vehicle.last_node_id,
        "last_node_sequence": vehicle.last_node_sequence_id,
        "last_seen": vehicle.last_seen.isoformat() if vehicle.last_seen else None,
        "factsheet": vehicle.factsheet,
    }
