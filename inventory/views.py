"""Pages of the inventory: stock and occupancy, discrepancies, CSV export and import."""

from django.contrib import messages
from django.http import Http404, HttpRequest, HttpResponse
from django.shortcuts import redirect, render
from django.views.decorators.http import require_POST

from fleet import roles
from fleet.access import require_permission
from fleet.exceptions import DomainError
from inventory import selectors, services
from inventory.models import LoadCarrier, Movement

MAX_UPLOAD = 5 * 1024 * 1024  # bytes; a CSV of 100,000 loads is well below this


@require_permission(roles.VIEW_OPERATIONS)
def stock(request: HttpRequest) -> HttpResponse:
    return render(
        request,
        "inventory/stock.html",
        {
            "locations": selectors.occupancy(),
            "loads": LoadCarrier.objects.select_related("location__station", "vehicle")[:1000],
            "discrepancies": selectors.open_discrepancies()[:200],
            "movements": Movement.objects.select_related(
                "load", "to_location__station", "to_vehicle"
            )[:50],
        },
    )


@require_permission(roles.VIEW_OPERATIONS)
def export(request: HttpRequest, kind: str) -> HttpResponse:
    if kind not in ("locations", "stock"):
        raise Http404
    response = HttpResponse(services.export_csv(kind), content_type="text/csv; charset=utf-8")
    response["Content-Disposition"] = f'attachment; filename="{kind}.csv"'
    return response


@require_POST
@require_permission(roles.ADMINISTER)
def import_(request: HttpRequest, kind: str) -> HttpResponse:
    upload = request.FILES.get("file")
    if upload is None or upload.size is None or upload.size > MAX_UPLOAD:
        messages.error(request, "choose a CSV file (at most 5 MB)")
        return redirect("inventory:stock")
    try:
        count = services.import_csv(kind, upload.read().decode("utf-8-sig"))
    except (DomainError, UnicodeDecodeError) as exc:
        messages.error(request, f"nothing imported: {exc}")
    else:
        messages.success(request, f"{count} {kind} rows imported")
    return redirect("inventory:stock")
