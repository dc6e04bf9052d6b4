"""The staff orders pages: list and filter orders with their reasons, create multi-stop orders,
cancel, reprioritise and reassign them, and set up recurring orders. Thin: every write is a
service call; a refused change comes back as a message, never as a half-done write."""

from typing import Any

from django.contrib import messages
from django.contrib.auth.models import User
from django.core.paginator import Paginator
from django.db.models import Q, QuerySet
from django.http import HttpRequest, HttpResponse
from django.shortcuts import get_object_or_404, redirect, render
from django.views.decorators.http import require_POST

from fleet import roles
from fleet.access import require_permission
from fleet.exceptions import DomainError
from orders import services
from orders.forms import (
    OrderCreateForm,
    OrderFilterForm,
    PriorityForm,
    ReassignForm,
    RecurringOrderForm,
    step_formset,
)
from orders.models import RecurringOrder, TransportOrder
from orders.services import StepSpec
from robots.models import Vehicle

PAGE_SIZE = 50


@require_permission(roles.VIEW_OPERATIONS)
def order_list(request: HttpRequest) -> HttpResponse:
    """Orders newest first with status, vehicle, steps and why they wait or failed."""
    form = OrderFilterForm(request.GET or None)
    orders = _filtered(form)
    page = Paginator(orders, PAGE_SIZE).get_page(request.GET.get("page"))
    context = {
        "form": form,
        "page": page,
        "vehicles": Vehicle.objects.order_by("serial_number"),
        "query": _query_without_page(request),
    }
    return render(request, "orders/list.html", context)


def _filtered(form: OrderFilterForm) -> QuerySet[TransportOrder]:
    orders = TransportOrder.objects.select_related(
        "vehicle", "intended_vehicle", "vehicle_type", "source", "destination"
    ).prefetch_related("steps__station")
    data = form.cleaned_data if form.is_bound and form.is_valid() else {}
    status = data.get("status", "")
    if status == "":
        orders = orders.filter(status__in=TransportOrder.OPEN_STATUSES)
    elif status != "ALL":
        orders = orders.filter(status=status)
    if data.get("station"):
        orders = orders.filter(steps__station__station_id=data["station"]).distinct()
    if data.get("vehicle"):
        orders = orders.filter(vehicle__serial_number=data["vehicle"])
    if data.get("q"):
        orders = orders.filter(
            Q(external_ref__icontains=data["q"]) | Q(load_id__icontains=data["q"])
        )
    return orders.order_by("-created_at", "-pk")


def _query_without_page(request: HttpRequest) -> str:
    query = request.GET.copy()
    query.pop("page", None)
    return query.urlencode()


@require_permission(roles.OPERATE_ORDERS)
def order_create(request: HttpRequest) -> HttpResponse:
    """A multi-stop order: up to six steps, blank rows ignored."""
    form = OrderCreateForm(request.POST or None)
    steps = step_formset(request.POST or None)
    if request.method == "POST" and form.is_valid() and steps.is_valid():
        specs = [
            StepSpec(
                station=row["station"],
                operation=row["operation"],
                action_type=row.get("action_type", ""),
            )
            for row in steps.cleaned_data
            if row.get("station")
        ]
        try:
            order = services.create_transport_order(
                steps=specs, created_by=request.user, **form.cleaned_data
            )
        except DomainError as exc:
            form.add_error(None, str(exc))
        else:
            messages.success(request, f"Order {order.pk} created.")
            return redirect("orders:list")
    return render(request, "orders/create.html", {"form": form, "steps": steps})


def _change(request: HttpRequest, pk: int, act: Any) -> HttpResponse:
    order = get_object_or_404(TransportOrder, pk=pk)
    try:
        message = act(order)
    except DomainError as exc:
        messages.error(request, f"Order {pk}: {exc}")
    else:
        messages.success(request, f"Order {pk}: {message}")
    return redirect(request.POST.get("next") or "orders:list")


@require_POST
@require_permission(roles.OPERATE_ORDERS)
def order_cancel(request: HttpRequest, pk: int) -> HttpResponse:
    def act(order: TransportOrder) -> str:
        order = services.cancel_transport_order(order=order, reason="staff", by=request.user)
        return "cancelled" if order.status == "CANCELLED" else "cancel requested from the vehicle"

    return _change(request, pk, act)


@require_POST
@require_permission(roles.OPERATE_ORDERS)
def order_priority(request: HttpRequest, pk: int) -> HttpResponse:
    form = PriorityForm(request.POST)

    def act(order: TransportOrder) -> str:
        if not form.is_valid():
            raise DomainError("priority must be a whole number from -1000 to 1000")
        priority = form.cleaned_data["priority"]
        services.update_order_priority(order=order, priority=priority, by=request.user)
        return f"priority {priority}"

    return _change(request, pk, act)


@require_POST
@require_permission(roles.OPERATE_ORDERS)
def order_reassign(request: HttpRequest, pk: int) -> HttpResponse:
    form = ReassignForm(request.POST)

    def act(order: TransportOrder) -> str:
        if not form.is_valid():
            raise DomainError("unknown vehicle")
        vehicle = form.cleaned_data["vehicle"]
        services.reassign_order(order=order, vehicle=vehicle, by=request.user)
        return f"reassigned to {vehicle or 'any vehicle'}"

    return _change(request, pk, act)


@require_permission(roles.VIEW_OPERATIONS, to_change=roles.OPERATE_ORDERS)
def recurring_list(request: HttpRequest) -> HttpResponse:
    """Recurring orders and a form for a new A → B one."""
    form = RecurringOrderForm(request.POST or None)
    if request.method == "POST" and form.is_valid():
        data = form.cleaned_data
        schedule = RecurringOrder(
            name=data["name"],
            map=data["source"].map,
            steps=[
                {"station": data["source"].station_id, "operation": "PICK"},
                {"station": data["destination"].station_id, "operation": "DROP"},
            ],
            interval_minutes=data["interval_minutes"],
            weekdays=sorted(int(d) for d in data["weekdays"]),
            window_start=data["window_start"],
            window_end=data["window_end"],
            priority=data["priority"],
            created_by=request.user if isinstance(request.user, User) else None,
        )
        try:
            services.save_recurring_order(schedule=schedule)
        except DomainError as exc:
            form.add_error(None, str(exc))
        else:
            messages.success(request, f"Recurring order {schedule.name!r} saved.")
            return redirect("orders:recurring")
    schedules = RecurringOrder.objects.select_related("map").order_by("name")
    return render(request, "orders/recurring.html", {"form": form, "schedules": schedules})
