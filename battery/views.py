"""Staff pages of the battery app: the fleet's batteries, chargers and queue; one vehicle's
history. They need VIEW_OPERATIONS; chargers and policies are changed in the admin."""

from django.http import HttpRequest, HttpResponse
from django.shortcuts import get_object_or_404, render

from battery import selectors
from battery.models import Charger, ChargeSession, VehicleEnergy
from fleet import roles
from fleet.access import require_permission
from robots.models import Vehicle


@require_permission(roles.VIEW_OPERATIONS)
def overview(request: HttpRequest) -> HttpResponse:
    return render(
        request,
        "battery/overview.html",
        {
            "vehicles": selectors.list_vehicle_energy(),
            "chargers": Charger.objects.select_related("station").order_by("station__station_id"),
            "booked": selectors.booked_vehicles(),
            "sessions": selectors.list_open_sessions(),
            "recent": ChargeSession.objects.select_related("vehicle", "charger__station")[:20],
            "alerts": selectors.open_alerts(),
        },
    )


@require_permission(roles.VIEW_OPERATIONS)
def vehicle_detail(request: HttpRequest, pk: int) -> HttpResponse:
    vehicle = get_object_or_404(Vehicle, pk=pk)
    samples = list(selectors.battery_history(vehicle=vehicle, limit=300))
    return render(
        request,
        "battery/vehicle.html",
        {
            "vehicle": vehicle,
            "energy": VehicleEnergy.objects.filter(vehicle=vehicle).first(),
            "samples": samples,
            "sparkline": _sparkline([s.charge for s in reversed(samples)]),
            "sessions": ChargeSession.objects.filter(vehicle=vehicle).select_related(
                "charger__station"
            )[:50],
        },
    )


def _sparkline(charges: list[float], width: int = 600, height: int = 80) -> str:
    """SVG polyline points of the charge over the samples (0–100 % bottom to top)."""
    if len(charges) < 2:
        return ""
    step = width / (len(charges) - 1)
    return " ".join(
        f"{i * step:.1f},{height - charge / 100 * height:.1f}" for i, charge in enumerate(charges)
    )
