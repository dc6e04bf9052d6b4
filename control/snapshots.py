"""Views of a LiveVehicle: a database row for the flusher and a browser row for the live page."""

import time
from typing import Any

import msgspec

import vda5050
from control.execution import LayoutIndex
from control.live import LiveVehicle
from control.traffic_link import TrafficLink
from control.traffic_support import vehicle_class


def row(vehicle: LiveVehicle) -> dict[str, Any]:
    """The `robots.Vehicle` snapshot fields (robots.services.SNAPSHOT_FIELDS) plus `pk`."""
    state, position = vehicle.state, vehicle.visual_position
    data: dict[str, Any] = {
        "pk": vehicle.pk,
        "connection": vehicle.connection,
        "protocol_version": vehicle.version,
        "interface_name": vehicle.interface_name,
        "last_seen": vehicle.last_seen,
        "clock_skew": vehicle.session.clock_skew,
        "protocol_counters": dict(vehicle.session.counters),
        "map_id": position.map_id if position else "",
        "x": position.x if position else None,
        "y": position.y if position else None,
        "theta": position.theta if position else None,
        "position_initialized": bool(position and position.position_initialized),
    }
    if state is None:
        return data | {
            "battery_charge": None,
            "charging": False,
            "driving": False,
            "paused": False,
            "operating_mode": "",
            "errors": [],
            "loads": [],
            "loads_known": False,
            "order_id": "",
            "order_update_id": None,
            "last_node_id": "",
            "last_node_sequence_id": None,
        }
    return data | {
        "battery_charge": state.battery_state.battery_charge,
        "charging": state.battery_state.charging,
        "driving": state.driving,
        "paused": bool(state.paused),
        "operating_mode": str(state.operating_mode),
        "errors": msgspec.to_builtins(state.errors),
        "loads": msgspec.to_builtins(state.loads or []),
        # F.32: `loads` omitted = unknown, [] = unloaded (stored as [] either way; not a column)
        "loads_known": state.loads is not None,
        "order_id": state.order_id,
        "order_update_id": state.order_update_id,
        "last_node_id": state.last_node_id,
        "last_node_sequence_id": state.last_node_sequence_id,
    }


def material(vehicle: LiveVehicle) -> tuple[Any, ...]:
    """What of a vehicle's snapshot other processes act on: dispatch (availability, mode,
    errors, loads, the order it drives), alerts and the stale-assignment check. Position,
    last node, battery charge and `last_seen` are left out: while a vehicle drives they change
    with every state, and only pages and counters read them from the database."""
    state, position = vehicle.state, vehicle.visual_position
    placed = (position.map_id, bool(position.position_initialized)) if position else None
    if state is None:
        return (vehicle.connection, vehicle.version, placed)
    return (
        *(vehicle.connection, vehicle.version, placed, state.driving, state.paused),
        *(state.operating_mode, state.battery_state.charging, state.errors, state.loads),
        *(state.order_id, state.order_update_id),
    )


def status_label(vehicle: LiveVehicle) -> str:
    """One word for the page's colour: offline, error, paused, charging, driving, busy, idle."""
    return _status(vehicle, vehicle.connection)


def _status(vehicle: LiveVehicle, connection: str) -> str:
    state = vehicle.state
    if connection != "ONLINE" or state is None:
        return "offline"
    if any(str(e.error_level) == "FATAL" for e in state.errors):
        return "error"
    if state.paused:
        return "paused"
    if state.battery_state.charging:
        return "charging"
    if state.driving:
        return "driving"
    return "idle" if vehicle.is_idle else "busy"


def browser_row(
    vehicle: LiveVehicle, layouts: dict[str, LayoutIndex], traffic: TrafficLink | None = None
) -> dict[str, Any]:
    """What the live page draws and lists for one vehicle, including its remaining route and,
    with traffic management, whom it waits for and the nodes it has reserved beyond its base.

    Sent for up to every vehicle 5 times a second, so kept compact: positions in millimetres,
    route points in centimetres. Built from scratch here; control's broadcasts use `live_row`,
    which gives the same row and rebuilds only what changed."""
    return _build(vehicle, RowParts(_layout_of(vehicle, layouts)), traffic)


def live_row(
    vehicle: LiveVehicle, layouts: dict[str, LayoutIndex], traffic: TrafficLink | None = None
) -> dict[str, Any]:
    """`browser_row(vehicle, layouts, traffic)`, made from the vehicle's previous live row by
    rebuilding only the fields whose inputs changed (kept in `vehicle.row_parts`).

    With 1,000 moving vehicles nearly every vehicle is in every broadcast, 5 times a second,
    and most of a row stays: a moving vehicle's route changes at each node it passes, its
    footprint with a factsheet, its state's fields with each state (a visualization message
    brings only a pose)."""
    layout = _layout_of(vehicle, layouts)
    parts = vehicle.row_parts
    if parts is None or parts.layout is not layout:  # a new or reloaded map starts afresh
        parts = vehicle.row_parts = RowParts(layout)
    return _build(vehicle, parts, traffic)


# The row's fields, in the order the page has always got them.
ROW_FIELDS = (
    *("id", "manufacturer", "serial", "status", "connection", "x", "y", "theta", "map", "size"),
    *("battery", "mode", "order", "transport_order", "last_node", "loaded", "errors", "base"),
    *("horizon", "waiting_for", "reserved", "clock_skew", "instant_actions"),
)
_UNSET = object()


class RowParts:
    """A vehicle's last live row and the inputs it was built from (compared by identity where
    control replaces them whole: a state, a pose and a factsheet arrive as new objects)."""

    __slots__ = (
        *("layout", "row", "state", "connection", "position", "node_states", "factsheet"),
        "reserved_ids",
    )

    def __init__(self, layout: LayoutIndex | None) -> None:
        self.layout = layout
        self.row: dict[str, Any] | None = None  # never changed once handed out
        self.state: object = _UNSET
        self.connection = ""
        self.position: object = _UNSET
        self.node_states: object = _UNSET
        self.factsheet: object = _UNSET
        self.reserved_ids: list[str] | None = None


def _layout_of(vehicle: LiveVehicle, layouts: dict[str, LayoutIndex]) -> LayoutIndex | None:
    position = vehicle.visual_position
    return layouts.get(position.map_id) if position is not None else None


def _build(vehicle: LiveVehicle, parts: RowParts, traffic: TrafficLink | None) -> dict[str, Any]:
    """The vehicle's row from `parts.row` with what changed since rebuilt (all, the first time)."""
    if parts.row is None:
        row = dict.fromkeys(ROW_FIELDS)
        row["manufacturer"], row["serial"] = vehicle.manufacturer, vehicle.serial_number
    else:
        row = parts.row.copy()
    row["id"] = vehicle.pk  # known once the flusher registered the vehicle
    state, connection = vehicle.state, vehicle.connection
    if state is not parts.state or connection != parts.connection:
        row["status"], row["connection"] = _status(vehicle, connection), connection
        parts.connection = connection
    if state is not parts.state:
        parts.state = state
        _state_fields(row, state)
        node_states = state.node_states if state is not None else None
        if node_states != parts.node_states:  # Structs compare field by field, in C
            parts.node_states = node_states
            row["base"], row["horizon"] = _route(state, parts.layout)
    if vehicle.visual_position is not parts.position:
        parts.position = position = vehicle.visual_position
        row["x"] = round(position.x, 3) if position else None
        row["y"] = round(position.y, 3) if position else None
        row["theta"] = round(position.theta, 3) if position else None
        row["map"] = position.map_id if position else None
    if vehicle.factsheet is not parts.factsheet:  # a factsheet message brings a new dict
        parts.factsheet = vehicle.factsheet
        footprint = vehicle_class(vehicle.factsheet)  # the factsheet's, or planning's default
        row["size"] = [round(footprint.length, 2), round(footprint.width, 2)]  # metres
    execution = vehicle.execution
    row["transport_order"] = execution.transport_order_id if execution else None
    _traffic_fields(row, vehicle, parts, traffic)
    row["clock_skew"] = vehicle.session.clock_skew
    row["instant_actions"] = _instant_actions(vehicle) if vehicle.instant_actions else []
    parts.row = row
    return row


def _state_fields(row: dict[str, Any], state: vda5050.State | None) -> None:
    if state is None:
        row.update(battery=None, mode=None, order=None, last_node=None, loaded=False, errors=[])
        return
    row["battery"] = round(state.battery_state.battery_charge, 1)
    row["mode"] = str(state.operating_mode)
    row["order"] = state.order_id
    row["last_node"] = state.last_node_id
    row["loaded"] = bool(state.loads)
    row["errors"] = [f"{e.error_level} {e.error_type}" for e in state.errors]


def _route(
    state: vda5050.State | None, layout: LayoutIndex | None
) -> tuple[list[list[float]], list[list[float]]]:
    """The points of the nodes still to drive: (base, horizon)."""
    base: list[list[float]] = []
    horizon: list[list[float]] = []
    if state is not None and layout is not None:
        for node_state in state.node_states:
            point = _node_point(layout, node_state.node_id)
            if point is not None:
                (base if node_state.released else horizon).append(point)
    return base, horizon


def _traffic_fields(
    row: dict[str, Any], vehicle: LiveVehicle, parts: RowParts, traffic: TrafficLink | None
) -> None:
    """Whom it waits for and its reserved nodes' points. Traffic is asked every time (it has no
    change signal per vehicle); only the points are reused while the reserved nodes stay."""
    layout = parts.layout
    if traffic is None or layout is None:
        row["waiting_for"], row["reserved"], parts.reserved_ids = [], [], None
        return
    row["waiting_for"] = traffic.waiting_for(vehicle)
    reserved_ids = traffic.reserved(vehicle)
    if reserved_ids != parts.reserved_ids:
        parts.reserved_ids = reserved_ids
        points = (_node_point(layout, node_id) for node_id in reserved_ids)
        row["reserved"] = [point for point in points if point is not None]


def _instant_actions(vehicle: LiveVehicle) -> list[dict[str, str]]:
    return [
        {"type": a.action_type, "status": a.status, "reason": a.reason}
        for a in list(vehicle.instant_actions.values())[-5:]
    ]


def compact_row(row: dict[str, Any]) -> dict[str, Any]:
    """A browser row for the live broadcast without its empty fields (None, "", []) and with
    the clock skew in centiseconds: a third fewer bytes per vehicle, 5 times a second. The live
    page reads a missing field as empty."""
    compact = {key: value for key, value in row.items() if value or value == 0}
    if "clock_skew" in compact:
        compact["clock_skew"] = round(compact["clock_skew"], 2)
    return compact


class LiveDeltas:
    """Turns control's broadcast rows into what the live page is sent: whole rows for vehicles
    seen for the first time and, every `keyframe_every`-th broadcast, for all in it; otherwise
    only the fields that changed since the vehicle's last broadcast, with None for a field that
    became empty. A moving vehicle's change is its pose: about 50 bytes instead of 300.

    The page replaces a vehicle with a whole row and merges a change into what it has; its
    first picture comes from the database (and again after a reconnect), so a page that joined
    late is complete with the next keyframe at the latest. The first broadcast after a pause of
    `pause_s` is a keyframe too: control builds no rows while no page is open (or nothing
    changed), and a page that opened meanwhile has only the database's picture, without routes.
    """

    def __init__(self, keyframe_every: int = 10, pause_s: float = 2.0) -> None:
        self.keyframe_every = keyframe_every
        self.pause_s = pause_s
        self.sent = 0
        self.sent_at = float("-inf")  # monotonic
        self.last: dict[tuple[Any, str, str], dict[str, Any]] = {}

    def payload(self, rows: list[dict[str, Any]]) -> dict[str, list[dict[str, Any]]]:
        """`{"vehicles": [whole rows], "changes": [changed fields with "id"]}` for `rows`."""
        now = time.monotonic()
        if now - self.sent_at > self.pause_s:
            self.sent = 0  # the keyframe cadence starts again from here
        self.sent_at = now
        keyframe = self.sent % self.keyframe_every == 0
        self.sent += 1
        whole: list[dict[str, Any]] = []
        changes: list[dict[str, Any]] = []
        for row in rows:
            compact = compact_row(row)
            key = (row["id"], row["manufacturer"], row["serial"])
            before = self.last.get(key)
            self.last[key] = compact
            if keyframe or before is None or row["id"] is None:
                whole.append(compact)
                continue
            change = {k: v for k, v in compact.items() if before.get(k) != v}
            change.update(dict.fromkeys(before.keys() - compact.keys()))
            if change:
                change["id"] = row["id"]
                changes.append(change)
        return {"vehicles": whole, "changes": changes}


def _node_point(layout: LayoutIndex, node_id: str) -> list[float] | None:
    """The node's browser point, made once per layout (rows share the list; it is only
    encoded, never changed): rounding every node of every route 5 times a second was a
    tenth of control's broadcast work with 1,000 vehicles."""
    point = layout.points.get(node_id)
    if point is None:
        place = layout.nodes.get(node_id)
        if place is None:
            return None
        point = layout.points[node_id] = _point(place.x, place.y)
    return point


def _point(x: float, y: float) -> list[float]:
    return [round(x, 2), round(y, 2)]
