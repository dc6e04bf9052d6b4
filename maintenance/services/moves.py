"""Drives to park (or maintenance) stations, which `control` carries out like orders."""

from django.db import IntegrityError, transaction
from django.utils import timezone

from fleet.control_queue import send_command
from fleet.exceptions import DomainError, InvalidRequestError
from maintenance.models import OPEN_MOVES, ServiceMove
from maps.models import Map, Station
from maps.selectors import load_graph
from robots.models import Vehicle
from traffic import NoRouteError

Status = ServiceMove.Status


def send_to_station(
    *,
    vehicle: Vehicle,
    station_id: str = "",
    kinds: tuple[str, ...] = (Station.Kind.PARK,),
    reason: str = "",
    command_id: int | None = None,
) -> ServiceMove:
    """Send `vehicle` to `station_id`, else to the nearest free station of `kinds` it can
    reach (free: nobody is sent there and no vehicle stands on it). A vehicle busy with an
    order drives there after it; one in a manual mode gets nothing until it is automatic
    again (control only sends orders to available vehicles)."""
    layout = Map.objects.filter(map_id=vehicle.map_id).first()
    if layout is None or not vehicle.last_node_id:
        raise InvalidRequestError(f"{vehicle} has no known position on a known map")
    graph = load_graph(map=layout)
    taken = set(
        ServiceMove.objects.filter(status__in=OPEN_MOVES).values_list("station_id", flat=True)
    )
    occupied = set(
        Vehicle.objects.filter(map_id=layout.map_id)
        .exclude(pk=vehicle.pk)
        .values_list("last_node_id", flat=True)
    )
    stations = Station.objects.filter(map=layout).select_related("node")
    if station_id:
        stations = stations.filter(station_id=station_id)
        if not stations:
            raise InvalidRequestError(f"no station {station_id} on {layout.map_id}")
    else:
        stations = stations.filter(kind__in=kinds)
    options = []
    for station in stations:
        if station.pk in taken or station.node.node_id in occupied:
            continue
        try:
            route = graph.shortest_path(vehicle.last_node_id, station.node.node_id)
        except NoRouteError:
            continue
        options.append((graph.path_length(route), station.station_id, station, route))
    if not options:
        raise DomainError(f"no free {'/'.join(kinds).lower()} station that {vehicle} can reach")
    _, _, station, route = min(options, key=lambda option: option[:2])
    try:
        with transaction.atomic():
            move = ServiceMove.objects.create(
                vehicle=vehicle,
                station=station,
                route=route,
                reason=reason[:200],
                command_id=command_id,
            )
    except IntegrityError:
        raise DomainError(f"{vehicle} is already on its way to a station") from None
    transaction.on_commit(lambda: send_command("order.assigned", service_move=move.pk))
    return move


_PROGRESS = {
    "sent": ({Status.ASSIGNED}, Status.DRIVING),
    "started": ({Status.ASSIGNED, Status.DRIVING}, Status.DRIVING),
    "finished": ({Status.ASSIGNED, Status.DRIVING}, Status.DONE),
    "failed": ({Status.ASSIGNED, Status.DRIVING}, Status.FAILED),
    "cancelled": ({Status.ASSIGNED, Status.DRIVING}, Status.CANCELLED),
    # The vehicle is no longer where the route starts: give up (staff may send it again).
    "requeued": ({Status.ASSIGNED, Status.DRIVING}, Status.FAILED),
}


def apply_move_progress(*, move_id: int, kind: str, reason: str = "") -> bool:
    """What `control` saw of a move: sent, started, arrived, failed or cancelled."""
    rule = _PROGRESS.get(kind)
    if rule is None:
        return False
    allowed, target = rule
    fields: dict[str, object] = {"status": target}
    if target not in {Status.DRIVING}:
        fields |= {"ended_at": timezone.now(), "note": reason[:200]}
    return bool(ServiceMove.objects.filter(pk=move_id, status__in=allowed).update(**fields))
