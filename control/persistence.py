"""The database side of `control`: loading on start, assigned orders, and batched flushes."""

import logging
from typing import Any

from django.db import close_old_connections, transaction

from control.execution import LayoutIndex, NodePlace, Progress
from control.ports import ActiveOrder, FlushBatch
from maps.models import Edge, Map, Node
from maps.selectors import edge_speed_limits
from orders import selectors as order_selectors
from orders import services as order_services
from orders.tasks import dispatch_pending_orders_task
from robots import services as robot_services
from robots.models import Vehicle

logger = logging.getLogger(__name__)


class DjangoStore:
    """Implements `control.controller.Store` with the ORM and the apps' services."""

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
            layouts[layout.map_id] = LayoutIndex(layout.map_id, nodes, edges, limits)
        return layouts

    def load_vehicles(self) -> list[dict[str, Any]]:
        close_old_connections()
        rows = Vehicle.objects.values(
            "pk", "manufacturer", "serial_number", "interface_name", "protocol_version", "dialect"
        )
        return [dict(row) for row in rows]

    def active_orders(self) -> list[ActiveOrder]:
        close_old_connections()
        return [
            ActiveOrder(
                transport_order_id=order.pk,
                vda_order_id=order.vda_order_id,
                vehicle_pk=order.vehicle_id,
                route=list(order.route),
                pickup_node=order.source.node.node_id,
                map_id=order.source.map.map_id,
                pick_station=order.source.station_id,
                drop_station=order.destination.station_id,
                load_id=order.load_id,
                load_type=order.load_type,
                cancel_requested=order.cancel_requested,
            )
            for order in order_selectors.list_active_orders()
            if order.vehicle_id is not None and order.route
        ]

    def flush(self, batch: FlushBatch) -> dict[tuple[str, str], int]:
        """Register new vehicles, bulk-update snapshots, then apply order progress in order."""
        close_old_connections()
        registered = robot_services.register_vehicles(
            identities=[v.key for v in batch.new_vehicles]
        )
        with transaction.atomic():
            robot_services.save_snapshots(snapshots=batch.snapshots)
            robot_services.save_factsheets(factsheets=batch.factsheets)
        for progress in batch.progress:
            _apply(progress)
        for outcome in batch.command_outcomes:
            if outcome.request is not None and outcome.request.isdigit():
                order_services.record_command_outcome(
                    command_id=int(outcome.request),
                    status=outcome.status,
                    result=outcome.reason,
                    action_id="" if outcome.status == "REFUSED" else outcome.action_id,
                )
        return registered

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
            dispatch_pending_orders_task.delay()
        except Exception:
            logger.exception("could not queue dispatch; beat runs it periodically")


def _apply(progress: Progress) -> None:
    order_id, detail = progress.order_id, progress.detail
    if progress.kind == "sent":
        order_services.mark_order_sent(order_id=order_id)
    elif progress.kind == "started":
        order_services.mark_order_started(order_id=order_id)
    elif progress.kind == "step":
        order_services.mark_step_reached(
            order_id=order_id, step=detail["step"], node_id=detail["node"]
        )
    elif progress.kind == "finished":
        order_services.mark_order_finished(order_id=order_id)
    elif progress.kind == "failed":
        order_services.mark_order_failed(order_id=order_id, reason=detail.get("reason", ""))
    elif progress.kind == "requeued":
        order_services.requeue_order(order_id=order_id, reason=detail.get("reason", ""))
    elif progress.kind == "cancelled":
        order_services.mark_order_cancelled(order_id=order_id)
