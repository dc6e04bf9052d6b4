"""The database side of `control`: loading on start, assigned orders, and batched flushes."""

import logging
from collections.abc import Iterable, Mapping, Sequence
from typing import Any

from django.conf import settings
from django.db import close_old_connections, transaction
from django.db.models import QuerySet
from django.utils.module_loading import import_string

from battery import selectors as battery_selectors
from battery import services as battery_services
from control.execution import LayoutIndex, NodePlace, Progress, StepPlan
from control.observer import SnapshotObserver
from control.ports import ActiveOrder, FlushBatch
from fleet.exceptions import DomainError
from maintenance import selectors as maintenance_selectors
from maintenance import services as maintenance_services
from maps.models import Edge, Map, Node, Station
from maps.selectors import edge_speed_limits
from orders import selectors as order_selectors
from orders import services as order_services
from orders.models import OrderStep, TransportOrder
from orders.services import dispatch_queue
from orders.services import floor as order_floor
from robots import services as robot_services
from robots.models import Vehicle

logger = logging.getLogger(__name__)


class DjangoStore:
    """Implements `control.controller.Store` with the ORM and the apps' services.

    With an `observer` (the running `control`), the floor observation of the flushed snapshots
    happens on the observer's thread; without one (tests, the embedded demo) inside the flush.
    """

    def __init__(self, observer: SnapshotObserver | None = None) -> None:
        self.observer = observer

    def load_layouts(self) -> dict[str, LayoutIndex]:
        close_old_connections()
        layouts: dict[str, LayoutIndex] = {}
        for layout in Map.objects.all():
            nodes = {
                n.node_id: NodePlace(n.x, n.y, n.theta, layout.map_id)
                for n in Node.objects.filter(map=layout)
            }
            edges = {
                (start, end): edge_id
                for edge_id, start, end in Edge.objects.filter(map=layout)
                .order_by("-length")
                .values_list("edge_id", "start__node_id", "end__node_id")
            }
            limits = {
                edge_id: limit
                for edge_id, limit in edge_speed_limits(map=layout).items()
                if limit is not None
            }
            parking = dict(
                Station.objects.filter(map=layout, kind=Station.Kind.PARK).values_list(
                    "station_id", "node__node_id"
                )
            )
            layouts[layout.map_id] = LayoutIndex(layout.map_id, nodes, edges, limits, parking)
        return layouts

    def load_vehicles(self) -> list[dict[str, Any]]:
        close_old_connections()
        rows = Vehicle.objects.values(
            "pk", "manufacturer", "serial_number", "interface_name", "protocol_version", "dialect"
        )
        return [dict(row) for row in rows]

    def active_orders(self) -> list[ActiveOrder]:
        close_old_connections()
        return _transport_orders(order_selectors.list_active_orders()) + _jobs(JOB_SOURCES.values())

    def assigned_orders(
        self, *, orders: list[int], charge_sessions: list[int], moves: list[int]
    ) -> list[ActiveOrder]:
        """The active orders and jobs with these ids (an `order.assigned` command names them):
        the few rows control needs to start them, instead of every active order (issue 11).
        Ids of orders no longer active are left out."""
        close_old_connections()
        found = []
        if orders:
            found += _transport_orders(order_selectors.list_active_orders().filter(pk__in=orders))
        wanted = {job_order_id("charge", pk) for pk in charge_sessions}
        wanted |= {job_order_id("park", pk) for pk in moves}
        kinds = {kind for kind, named in (("charge", charge_sessions), ("park", moves)) if named}
        if kinds:
            found += [job for job in _jobs(kinds) if job.transport_order_id in wanted]
        return found

    def flush(self, batch: FlushBatch) -> dict[tuple[str, str], int]:
        """Register new vehicles, bulk-update snapshots, then apply order progress in order."""
        close_old_connections()
        registered = robot_services.register_vehicles(
            identities=[v.key for v in batch.new_vehicles]
        )
        # Every order and vehicle event of the batch asks for the webhook subscriptions: one
        # read for the flush instead of a query per event (3 % of control's CPU under load).
        with order_services.subscriptions_read_once():
            self._apply_batch(batch)
        return registered

    def _apply_batch(self, batch: FlushBatch) -> None:
        with transaction.atomic():
            # Vehicle webhooks compare with the rows before they change (never raises).
            order_services.emit_vehicle_changes(snapshots=batch.snapshots)
            robot_services.save_snapshots(snapshots=batch.snapshots)
            robot_services.save_factsheets(factsheets=batch.factsheets)
        for progress in batch.progress:
            _apply(progress)
        # Alerts and inventory watch the saved snapshots after the progress (so a finished pick
        # is in the stock before state.loads is compared). With an observer this happens on its
        # thread: an alert flood must not hold up order sync and publishing (issue 11).
        if self.observer is not None:
            self.observer.submit(batch.snapshots)
        else:
            observe_floor(batch.snapshots)
        for command in batch.job_requests:
            _open_job(command)
        for outcome in batch.command_outcomes:
            if outcome.request is not None and outcome.request.isdigit():
                order_services.record_command_outcome(
                    command_id=int(outcome.request),
                    status=outcome.status,
                    result=outcome.reason,
                    action_id="" if outcome.status == "REFUSED" else outcome.action_id,
                )
        if batch.traffic_waits:  # last: a failure above retries the batch without doubling them
            _record_traffic_waits(batch.traffic_waits)

    def layouts_revision(self) -> object:
        """Changes whenever a map is added, removed or edited (zones included)."""
        close_old_connections()
        return sorted(Map.objects.values_list("map_id", "revision"))

    def vehicle_dialects(self) -> dict[int, str]:
        close_old_connections()
        rows = Vehicle.objects.exclude(dialect=Vehicle.Dialect.STANDARD).values_list(
            "pk", "dialect"
        )
        return dict(rows)

    def request_dispatch(self) -> None:
        try:
            dispatch_queue.request_dispatch()  # coalesced with the other requests
        except Exception:
            logger.exception("could not queue dispatch; beat runs it periodically")


def observe_floor(snapshots: Sequence[Mapping[str, Any]]) -> None:
    """Alerts, inventory (issue 8), battery history and maintenance counters (issue 7) from
    saved snapshots; each part logs its own failures and never raises."""
    order_floor.observe_fleet(snapshots=snapshots)
    battery_services.observe_snapshots(snapshots=snapshots)
    maintenance_services.observe_snapshots(snapshots=snapshots)


# What control reads of a transport order, every second: plain columns, no model instances
# (building them with their stations, nodes and steps was half of the 1 s sync, docs/LOAD.md).
_ORDER_COLUMNS = (
    *("pk", "vda_order_id", "vehicle_id", "route", "route_steps", "source__node__node_id"),
    *("source__map__map_id", "source__station_id", "destination__station_id", "load_id"),
    *("load_type", "cancel_requested"),
)
_STEP_COLUMNS = ("order_id", "operation", "action_type", "station__station_id", "parameters")


def _transport_orders(orders: QuerySet[TransportOrder]) -> list[ActiveOrder]:
    """Assigned or running transport orders (from `list_active_orders`) as control sees them."""
    rows = [
        row
        for row in orders.prefetch_related(None).values_list(*_ORDER_COLUMNS)
        if row[2] is not None and row[3]  # a vehicle and a route
    ]
    steps = _steps_of([row[0] for row in rows])
    return [
        ActiveOrder(
            transport_order_id=pk,
            vda_order_id=vda_order_id,
            vehicle_pk=vehicle_pk,
            route=list(route),
            pickup_node=pickup_node,
            map_id=map_id,
            pick_station=pick_station,
            drop_station=drop_station,
            load_id=load_id,
            load_type=load_type,
            cancel_requested=cancel_requested,
            steps=_step_plans(steps.get(pk, []), route_steps),
        )
        for (
            pk,
            vda_order_id,
            vehicle_pk,
            route,
            route_steps,
            pickup_node,
            map_id,
            pick_station,
            drop_station,
            load_id,
            load_type,
            cancel_requested,
        ) in rows
    ]


def _steps_of(order_ids: list[int]) -> dict[int, list[tuple[Any, ...]]]:
    """Each order's steps in order, as `_STEP_COLUMNS` rows (in chunks: SQLite's variables)."""
    found: dict[int, list[tuple[Any, ...]]] = {}
    for start in range(0, len(order_ids), 500):
        chunk = order_ids[start : start + 500]
        rows = OrderStep.objects.filter(order_id__in=chunk).order_by("order_id", "index")
        for row in rows.values_list(*_STEP_COLUMNS):
            found.setdefault(row[0], []).append(row)
    return found


def _step_plans(steps: list[tuple[Any, ...]], route_steps: Any) -> tuple[StepPlan, ...]:
    """The order's stops at the route indices dispatch recorded; none for an order assigned
    before steps existed (control then picks at the source and drops at the end)."""
    indices = list(route_steps or [])
    if not steps or len(indices) != len(steps):
        return ()
    return tuple(
        StepPlan(index, _action_type(operation, action_type), station, dict(parameters))
        for (_, operation, action_type, station, parameters), index in zip(
            steps, indices, strict=True
        )
    )


def _action_type(operation: str, action_type: str) -> str:
    """`OrderStep.vda_action_type` from the row's columns."""
    return action_type if operation == OrderStep.Operation.ACTION else operation.lower()


# Jobs the system creates besides transport orders travel as orders with negative ids:
# -(2·pk) for a battery charge session, -(2·pk + 1) for a maintenance move to a station.
JOB_SOURCES = {0: "charge", 1: "park"}


def _record_traffic_waits(episodes: list[dict[str, Any]]) -> None:
    """Hand finished traffic waits to the recorder named in settings (the reports app)."""
    recorder = getattr(settings, "FLEET_TRAFFIC_WAIT_RECORDER", "")
    if recorder:
        import_string(recorder)(episodes=episodes)


def job_order_id(kind: str, pk: int) -> int:
    return -(2 * pk + (1 if kind == "park" else 0))


def _jobs(kinds: Iterable[str]) -> list[ActiveOrder]:
    """Charge sessions driving to their point and moves to a park station, as orders (only
    the `kinds` asked for: "charge", "park")."""
    kinds = set(kinds)
    jobs = []
    if "charge" in kinds:
        jobs += [("charge", job["session"], job) for job in battery_selectors.list_charge_jobs()]
    if "park" in kinds:
        jobs += [("park", job["move"], job) for job in maintenance_selectors.list_move_jobs()]
    return [
        ActiveOrder(
            transport_order_id=job_order_id(kind, int(pk)),
            vda_order_id=str(job["vda_order_id"]),
            vehicle_pk=int(job["vehicle"]),
            route=list(job["route"]),
            pickup_node=str(job["route"][-1]),
            map_id=str(job["map_id"]),
            pick_station=str(job["station"]),
            drop_station=str(job["station"]),
            kind=kind,
        )
        for kind, pk, job in jobs
    ]


def _open_job(command: dict[str, Any]) -> None:
    """A staff `vehicle.charge` command becomes a queued charge session, `vehicle.park` a move
    to a park station; or the command is refused with the reason."""
    request = command.get("command")
    station = str(command.get("station") or "")
    try:
        if command.get("kind") == "vehicle.park":
            vehicle = Vehicle.objects.get(pk=int(command.get("vehicle", -1)))
            move = maintenance_services.send_to_station(
                vehicle=vehicle,
                station_id=station,
                reason=str(command.get("reason") or "sent by staff"),
                command_id=request if isinstance(request, int) else None,
            )
            status, result = "RUNNING", f"on its way to {move.station.station_id}"
        else:
            session = battery_services.request_charge(
                vehicle_id=int(command.get("vehicle", -1)),
                station_id=station,
                command_id=request if isinstance(request, int) else None,
            )
            status, result = "RUNNING", f"charge session {session.pk} queued"
    except (DomainError, Vehicle.DoesNotExist, ValueError, TypeError) as exc:
        # Refused, never raised: a bad command must not fail (and so repeat) the whole flush.
        status, result = "REFUSED", str(exc) or type(exc).__name__
    if isinstance(request, int):
        order_services.record_command_outcome(command_id=request, status=status, result=result)


def _apply(progress: Progress) -> None:
    order_id, detail = progress.order_id, progress.detail
    if order_id < 0:  # a charge session or a move (see _jobs)
        pk, source = divmod(-order_id, 2)
        reason = detail.get("reason", "")
        if JOB_SOURCES[source] == "park":
            maintenance_services.apply_move_progress(move_id=pk, kind=progress.kind, reason=reason)
        else:
            battery_services.apply_charge_progress(session_id=pk, kind=progress.kind, reason=reason)
        return
    if progress.kind == "sent":
        order_services.mark_order_sent(order_id=order_id)
    elif progress.kind == "started":
        order_services.mark_order_started(order_id=order_id)
    elif progress.kind == "step":
        index = detail.get("index")
        order_services.mark_step_reached(
            order_id=order_id,
            step=detail["step"],
            node_id=detail["node"],
            index=int(index) if index is not None and index.isdigit() else None,
        )
    elif progress.kind == "finished":
        order_services.mark_order_finished(order_id=order_id)
    elif progress.kind == "failed":
        order_services.mark_order_failed(order_id=order_id, reason=detail.get("reason", ""))
    elif progress.kind == "requeued":
        order_services.requeue_order(order_id=order_id, reason=detail.get("reason", ""))
    elif progress.kind == "cancelled":
        order_services.mark_order_cancelled(order_id=order_id)
