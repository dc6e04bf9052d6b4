"""The orders board: queued, running, failed (with the reasons from each order's timeline) and
finished today, side by side, with cancel and reprioritise on every open order. The search list
of every order stays at `orders:all`; the writes are the list's views (orders.views)."""

from dataclasses import dataclass, field
from datetime import datetime, time, timedelta

from django.db.models import Prefetch, QuerySet
from django.http import HttpRequest, HttpResponse
from django.shortcuts import render
from django.utils import timezone

from fleet import roles
from fleet.access import require_permission
from orders import views
from orders.models import OrderEvent, OrderStep, TransportOrder

COLUMN_LIMIT = 100  # orders shown per column; the count above each column is the full one
FAILED_WINDOW = timedelta(hours=24)
TIMELINE_REASONS = {
    OrderEvent.Kind.FAILED,
    OrderEvent.Kind.REQUEUED,
    OrderEvent.Kind.CANCEL_REQUESTED,
    OrderEvent.Kind.CANCELLED,
}


@dataclass(frozen=True)
class BoardCard:
    """An order on the board with the reasons its timeline gives (failed orders only)."""

    order: TransportOrder
    reasons: list[str] = field(default_factory=list)


@dataclass
class BoardColumn:
    """One column of the board: its cards (at most COLUMN_LIMIT) and how many orders there are."""

    key: str
    title: str
    cards: list[BoardCard]
    total: int
    hint: str = ""


def _orders() -> QuerySet[TransportOrder]:
    return TransportOrder.objects.select_related(
        "vehicle", "intended_vehicle", "vehicle_type", "source", "destination"
    ).prefetch_related(Prefetch("steps", queryset=OrderStep.objects.select_related("station")))


def _column(key: str, title: str, orders: QuerySet[TransportOrder], hint: str) -> BoardColumn:
    cards = [BoardCard(order) for order in orders[:COLUMN_LIMIT]]
    return BoardColumn(key, title, cards, orders.count(), hint)


def timeline_reasons(order_ids: list[int]) -> dict[int, list[str]]:
    """Why each order failed or went back to the queue, oldest first, from its timeline."""
    reasons: dict[int, list[str]] = {}
    events = OrderEvent.objects.filter(order_id__in=order_ids, kind__in=TIMELINE_REASONS)
    for event in events.order_by("at", "pk"):
        detail = event.detail or {}
        why = detail.get("reason") or detail.get("error") or ""
        text = f"{event.at:%H:%M:%S} {event.get_kind_display()}" + (f": {why}" if why else "")
        reasons.setdefault(event.order_id, []).append(text)
    return reasons


def board_columns(*, now: datetime | None = None) -> list[BoardColumn]:
    """The four columns: queued by priority, running, failed in the last 24 h, finished today."""
    now = now or timezone.now()
    today = timezone.make_aware(datetime.combine(timezone.localdate(now), time.min))
    orders = _orders()
    failed = _column(
        "failed",
        "Failed",
        orders.filter(
            status=TransportOrder.Status.FAILED, finished_at__gte=now - FAILED_WINDOW
        ).order_by("-finished_at", "-pk"),
        "last 24 hours",
    )
    reasons = timeline_reasons([card.order.pk for card in failed.cards])
    failed.cards = [BoardCard(card.order, reasons.get(card.order.pk, [])) for card in failed.cards]
    return [
        _column(
            "queued",
            "Queued",
            orders.filter(status=TransportOrder.Status.NEW).order_by(
                "-priority", "deadline", "created_at", "pk"
            ),
            "highest priority first",
        ),
        _column(
            "running",
            "Running",
            orders.filter(status__in=TransportOrder.ACTIVE_STATUSES).order_by("assigned_at", "pk"),
            "assigned or driving",
        ),
        failed,
        _column(
            "finished",
            "Finished today",
            orders.filter(status=TransportOrder.Status.FINISHED, finished_at__gte=today).order_by(
                "-finished_at", "-pk"
            ),
            "newest first",
        ),
    ]


LIST_PARAMETERS = {"view", "status", "station", "vehicle", "q", "page"}


def orders_page(request: HttpRequest) -> HttpResponse:
    """`/orders/`: the board, or the searchable list when the query asks for it (`?view=list`
    or any of the list's filters, so filtered links keep working)."""
    if LIST_PARAMETERS & set(request.GET):
        return views.order_list(request)
    return order_board(request)


@require_permission(roles.VIEW_OPERATIONS)
def order_board(request: HttpRequest) -> HttpResponse:
    """The board; actions post to the list's cancel/priority views and come back here."""
    return render(request, "orders/board.html", {"columns": board_columns()})
