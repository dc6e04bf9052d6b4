"""Operations pages: the fleet overview and the vehicles list (read-only, tablet-sized)."""

from django import forms
from django.http import HttpRequest, HttpResponse
from django.shortcuts import render

from control import operations
from fleet import roles
from fleet.access import require_permission
from maps.models import VehicleType


class VehicleFilterForm(forms.Form):
    """Filters and sort of the vehicles list (all optional; GET, so a filtered list is a link)."""

    state = forms.ChoiceField(
        choices=[("", "any state"), *operations.VEHICLE_STATES], required=False
    )
    vehicle_type = forms.ChoiceField(choices=[], required=False, label="Type")
    connection = forms.ChoiceField(
        choices=[("", "any connection"), *operations.CONNECTIONS], required=False
    )
    battery_below = forms.FloatField(
        required=False, min_value=0, max_value=100, label="Battery below %"
    )
    q = forms.CharField(max_length=100, required=False, label="Serial or name")
    sort = forms.ChoiceField(
        choices=[(key, key.replace("_", " ")) for key in operations.SORT_KEYS], required=False
    )
    desc = forms.BooleanField(required=False, label="Descending")

    def __init__(self, *args: object, **kwargs: object) -> None:
        super().__init__(*args, **kwargs)  # type: ignore[arg-type]
        types = VehicleType.objects.order_by("type_id").values_list("type_id", flat=True)
        self.fields["vehicle_type"].choices = [("", "any type")] + [(t, t) for t in types]  # type: ignore[attr-defined]

    def query(self) -> operations.VehicleQuery:
        data = self.cleaned_data if self.is_valid() else {}
        return operations.VehicleQuery(
            state=data.get("state") or "",
            vehicle_type=data.get("vehicle_type") or "",
            connection=data.get("connection") or "",
            battery_below=data.get("battery_below"),
            search=data.get("q") or "",
            sort=data.get("sort") or "serial",
            descending=bool(data.get("desc")),
        )


@require_permission(roles.VIEW_OPERATIONS)
def overview_page(request: HttpRequest) -> HttpResponse:
    """Vehicles by state, orders by status, open alerts by severity, chargers in use."""
    return render(request, "control/overview.html", {"overview": operations.get_overview()})


@require_permission(roles.VIEW_OPERATIONS)
def vehicles_page(request: HttpRequest) -> HttpResponse:
    """Every vehicle with state, type, connection, battery and order; filtered and sorted."""
    form = VehicleFilterForm(request.GET or None)
    query = form.query() if form.is_bound else operations.VehicleQuery()
    rows = operations.list_vehicles()
    shown = operations.filter_vehicles(rows, query)
    params = request.GET.copy()
    for key in ("sort", "desc"):
        params.pop(key, None)
    context = {
        "form": form,
        "rows": shown,
        "total": len(rows),
        "query": query,
        "filters": params.urlencode(),
        "columns": [
            ("serial", "Vehicle"),
            ("state", "State"),
            ("type", "Type"),
            ("connection", "Connection"),
            ("battery", "Battery"),
            ("last_seen", "Last update"),
        ],
    }
    return render(request, "control/vehicles.html", context)
