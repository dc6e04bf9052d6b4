"""Commands to vehicles: recorded as `VehicleCommand` rows and queued for `control`, which
publishes what the vehicle needs. The web process never talks to vehicles itself."""

import re
from typing import Any

from django.contrib.auth.base_user import AbstractBaseUser
from django.contrib.auth.models import AnonymousUser, User
from django.db import transaction
from django.utils import timezone

from fleet import audit
from fleet.control_queue import send_command
from fleet.exceptions import DomainError, InvalidRequestError
from maps.models import Map, Station
from maps.selectors import load_graph
from orders.models import TransportOrder, VehicleCommand
from orders.services.webhooks import emit_event
from robots.models import Vehicle

Kind = VehicleCommand.Kind
Status = VehicleCommand.Status
ACTION_TYPE = re.compile(r"^[A-Za-z][A-Za-z0-9_.\-]{0,63}$")
# Instant actions with a command or a workflow of their own.
RESERVED_ACTIONS = {
    "cancelOrder": "cancel the transport order instead (POST /api/v1/orders/<id>/cancel/)",
    "startPause": "use the pause command",
    "stopPause": "use the resume command",
}
User_ = AbstractBaseUser | AnonymousUser | None


def pause_vehicle(*, vehicle: Vehicle, by: User_ = None) -> VehicleCommand:
    """Ask the vehicle to pause (VDA 5050 instant action startPause); dispatch skips it while
    its state reports it paused."""
    return _queue(vehicle, Kind.PAUSE, {}, by)


def resume_vehicle(*, vehicle: Vehicle, by: User_ = None) -> VehicleCommand:
    """Ask a paused vehicle to go on (instant action stopPause)."""
    return _queue(vehicle, Kind.RESUME, {}, by)


def send_vehicle_to_charge(
    *, vehicle: Vehicle, station: Station | None = None, by: User_ = None
) -> VehicleCommand:
    """Send an idle vehicle to a charging station: `station`, else the nearest it can reach."""
    target = _destination(vehicle, station, Station.Kind.CHARGE)
    return _queue(vehicle, Kind.CHARGE, _place(target), by)


def send_vehicle_to_park(
    *, vehicle: Vehicle, station: Station | None = None, by: User_ = None
) -> VehicleCommand:
    """Send an idle vehicle to a parking station: `station`, else the nearest it can reach."""
    target = _destination(vehicle, station, Station.Kind.PARK)
    return _queue(vehicle, Kind.PARK, _place(target), by)


def request_instant_action(
    *,
    vehicle: Vehicle,
    action_type: str,
    parameters: dict[str, Any] | None = None,
    by: User_ = None,
) -> VehicleCommand:
    """Have control send one VDA 5050 instant action. When the vehicle's factsheet lists its
    actions, the action must be one it offers as INSTANT."""
    if not ACTION_TYPE.match(action_type):
        raise InvalidRequestError(f"{action_type!r} is not a valid action type")
    if action_type in RESERVED_ACTIONS:
        raise InvalidRequestError(f"{action_type}: {RESERVED_ACTIONS[action_type]}")
    offered = _instant_actions(vehicle)
    if offered is not None and action_type not in offered:
        raise InvalidRequestError(
            f"{vehicle} does not offer {action_type} as an instant action (factsheet)"
        )
    payload = {"action_type": action_type, "parameters": parameters or {}}
    return _queue(vehicle, Kind.INSTANT_ACTION, payload, by)


@transaction.atomic
def _queue(vehicle: Vehicle, kind: str, parameters: dict[str, Any], by: User_) -> VehicleCommand:
    if vehicle.connection != Vehicle.Connection.ONLINE:
        raise DomainError(f"{vehicle} is {vehicle.connection}: commands reach connected vehicles")
    command = VehicleCommand.objects.create(
        vehicle=vehicle,
        kind=kind,
        parameters=parameters,
        requested_by=by if isinstance(by, User) else None,
    )
    payload = {"vehicle": vehicle.pk, "command": command.pk, **parameters}
    audit.record(
        "vehicle.command",
        target_type="vehicle",
        target_id=vehicle,
        detail={"kind": kind, "command": command.pk, **parameters},
    )
    transaction.on_commit(lambda: send_command(kind, **payload), robust=True)
    emit_event(
        event_type="vehicle.command_queued",
        data=lambda: {
            "vehicle": {
                "id": vehicle.pk,
                "manufacturer": vehicle.manufacturer,
                "serial_number": vehicle.serial_number,
                "name": vehicle.name,
            },
            "command": {"id": command.pk, "kind": kind, "parameters": parameters},
        },
    )
    return command


def _destination(vehicle: Vehicle, station: Station | None, kind: str) -> Station:
    active = TransportOrder.objects.filter(
        vehicle=vehicle, status__in=TransportOrder.ACTIVE_STATUSES
    ).first()
    if active is not None:
        raise DomainError(f"{vehicle} has transport order {active.pk}; cancel it first")
    if not vehicle.is_available:
        raise DomainError(f"{vehicle} is not available (mode, error, pause or position)")
    layout = Map.objects.filter(map_id=vehicle.map_id).first()
    if layout is None:
        raise InvalidRequestError(f"{vehicle} is on map {vehicle.map_id!r}, which is not known")
    if station is not None:
        if station.kind != kind or station.map_id != layout.pk:
            raise InvalidRequestError(f"{station.station_id} is not a {kind} station on {layout}")
        return station
    graph = load_graph(map=layout)
    options = [
        (distances[vehicle.last_node_id], s.station_id, s)
        for s in Station.objects.filter(map=layout, kind=kind).select_related("node")
        if vehicle.last_node_id in (distances := graph.distances_to(s.node.node_id))
    ]
    if not options:
        raise InvalidRequestError(f"no {kind} station that {vehicle} can reach")
    return min(options, key=lambda option: option[:2])[2]


def _place(station: Station) -> dict[str, Any]:
    return {"station": station.station_id, "node": station.node.node_id, "map": station.map.map_id}


def _instant_actions(vehicle: Vehicle) -> set[str] | None:
    """Action types the factsheet offers as INSTANT, or None when it does not list actions."""
    features = (vehicle.factsheet or {}).get("protocolFeatures") or {}
    actions = features.get("agvActions")
    if not isinstance(actions, list):
        return None
    return {
        str(action.get("actionType"))
        for action in actions
        if isinstance(action, dict) and "INSTANT" in (action.get("actionScopes") or [])
    }


_OUTCOMES = {
    "SENT": Status.SENT,
    "REFUSED": Status.REFUSED,
    "WAITING": Status.SENT,
    "INITIALIZING": Status.RUNNING,
    "RUNNING": Status.RUNNING,
    "PAUSED": Status.RUNNING,
    "FINISHED": Status.FINISHED,
    "FAILED": Status.FAILED,
}


def record_command_outcome(
    *, command_id: int, status: str, result: str = "", action_id: str = ""
) -> None:
    """Control's word on a command: sent, refused (with the reason), or the VDA 5050 action
    status the vehicle reported. Unknown statuses and finished commands are left alone."""
    target = _OUTCOMES.get(status)
    if target is None:
        return
    VehicleCommand.objects.filter(pk=command_id).exclude(
        status__in=[Status.FINISHED, Status.FAILED, Status.REFUSED]
    ).update(status=target, result=result[:2000], action_id=action_id, updated_at=timezone.now())
