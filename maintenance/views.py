"""Staff pages of maintenance: due and open work, one vehicle (counters, service history,
errors, out of service and back) and one work order (advance it, notes, parts, files).
Reading needs VIEW_OPERATIONS; changing needs MAINTAIN_VEHICLES (fleet.roles)."""

from django.contrib import messages
from django.http import HttpRequest, HttpResponse
from django.shortcuts import get_object_or_404, redirect, render
from django.views.decorators.http import require_POST

from fleet import roles
from fleet.access import require_permission
from fleet.exceptions import DomainError
from maintenance import selectors, services
from maintenance.forms import AdvanceForm, NewWorkOrderForm, OutOfServiceForm
from maintenance.models import ErrorRecord, VehicleCounters, WorkOrder
from robots.models import Vehicle


@require_permission(roles.VIEW_OPERATIONS)
def overview(request: HttpRequest) -> HttpResponse:
    counters = {c.vehicle_id: c for c in VehicleCounters.objects.all()}
    vehicles = list(Vehicle.objects.order_by("manufacturer", "serial_number"))
    reasons = selectors.out_of_service(vehicle_ids=[v.pk for v in vehicles])
    return render(
        request,
        "maintenance/overview.html",
        {
            "work_orders": selectors.list_open_work_orders().order_by("due_at"),
            "overdue": set(selectors.list_overdue_work_orders().values_list("pk", flat=True)),
            "rows": [(v, counters.get(v.pk), reasons.get(v.pk)) for v in vehicles],
        },
    )


@require_permission(roles.VIEW_OPERATIONS)
def vehicle_detail(request: HttpRequest, pk: int) -> HttpResponse:
    vehicle = get_object_or_404(Vehicle, pk=pk)
    return render(
        request,
        "maintenance/vehicle.html",
        {
            "vehicle": vehicle,
            "counters": VehicleCounters.objects.filter(vehicle=vehicle).first(),
            "reason": selectors.out_of_service(vehicle_ids=[pk]).get(pk),
            "history": selectors.service_history(vehicle=vehicle),
            "stats": selectors.error_stats(vehicle=vehicle),
            "errors": ErrorRecord.objects.filter(vehicle=vehicle)[:50],
            "work_orders": WorkOrder.objects.filter(vehicle=vehicle)[:50],
            "out_form": OutOfServiceForm(),
            "new_form": NewWorkOrderForm(),
        },
    )


@require_POST
@require_permission(roles.MAINTAIN_VEHICLES)
def vehicle_service(request: HttpRequest, pk: int) -> HttpResponse:
    """Take out of service (with a reason), return to service, or open a work order."""
    vehicle = get_object_or_404(Vehicle, pk=pk)
    action = request.POST.get("action")
    try:
        if action == "out":
            form = OutOfServiceForm(request.POST)
            if not form.is_valid():
                raise DomainError("say why the vehicle is taken out of service")
            services.take_out_of_service(
                vehicle=vehicle,
                reason=form.cleaned_data["reason"],
                send_to=form.cleaned_data["send_to"],
                by=request.user,
            )
        elif action == "back":
            services.return_to_service(vehicle=vehicle, by=request.user)
        elif action == "work_order":
            new = NewWorkOrderForm(request.POST)
            if not new.is_valid():
                raise DomainError("a work order needs a title")
            services.create_work_order(vehicle=vehicle, by=request.user, **new.cleaned_data)
        else:
            raise DomainError(f"unknown action {action!r}")
    except DomainError as exc:
        messages.error(request, str(exc))
    return redirect("maintenance:vehicle", pk=pk)


@require_permission(roles.VIEW_OPERATIONS, to_change=roles.MAINTAIN_VEHICLES)
def work_order_detail(request: HttpRequest, pk: int) -> HttpResponse:
    work_order = get_object_or_404(WorkOrder.objects.select_related("vehicle", "plan"), pk=pk)
    form = AdvanceForm(initial={"status": work_order.status})
    if request.method == "POST":
        form = AdvanceForm(request.POST, request.FILES)
        if form.is_valid():
            try:
                services.advance_work_order(
                    work_order=work_order,
                    status=form.cleaned_data["status"],
                    notes=form.cleaned_data["notes"],
                    parts=form.parts(),
                    by=request.user,
                )
                if form.cleaned_data.get("attachment"):
                    services.add_attachment(
                        work_order=work_order, file=form.cleaned_data["attachment"]
                    )
                return redirect("maintenance:work_order", pk=pk)
            except DomainError as exc:
                form.add_error(None, str(exc))
    return render(
        request,
        "maintenance/work_order.html",
        {"work_order": work_order, "form": form, "attachments": work_order.attachments.all()},
    )
