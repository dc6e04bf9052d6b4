"""Pages of the alerts app: the list (acknowledge/resolve with a comment) and the banner feed."""

from django.contrib import messages
from django.http import HttpRequest, HttpResponse, JsonResponse
from django.shortcuts import redirect, render
from django.views.decorators.http import require_POST

from alerts import selectors, services
from alerts.models import Alert, Severity, Source
from fleet import roles
from fleet.access import require_permission
from fleet.exceptions import DomainError


@require_permission(roles.VIEW_OPERATIONS)
def alert_list(request: HttpRequest) -> HttpResponse:
    show = request.GET.get("show", "open")
    alerts = selectors.open_alerts() if show == "open" else Alert.objects.select_related("vehicle")
    source = request.GET.get("source", "")
    if source in Source.values:
        alerts = alerts.filter(source=source)
    severity = request.GET.get("severity", "")
    if severity in Severity.values:
        alerts = alerts.filter(severity=severity)
    if show in Alert.Status.values:  # one state: OPEN (unacknowledged), ACKNOWLEDGED, RESOLVED
        alerts = alerts.filter(status=show)
    vehicle = request.GET.get("vehicle", "").strip()[:100]
    if vehicle:
        alerts = alerts.filter(vehicle__serial_number__icontains=vehicle)
    return render(
        request,
        "alerts/list.html",
        {
            "alerts": alerts.order_by("-raised_at")[:500],
            "show": show,
            "sources": Source.choices,
            "severities": Severity.choices,
            "source": source,
            "severity": severity,
            "states": Alert.Status.choices,
            "vehicle": vehicle,
        },
    )


@require_POST
@require_permission(roles.ACKNOWLEDGE_ALERTS)
def alert_action(request: HttpRequest, pk: str, action: str) -> HttpResponse:
    comment = request.POST.get("comment", "")[:2000]
    try:
        if action == "acknowledge":
            services.acknowledge_alert(alert_id=int(pk), user=request.user, comment=comment)
        else:
            services.resolve_by_user(alert_id=int(pk), user=request.user, comment=comment)
    except DomainError as exc:
        messages.error(request, str(exc))
    return redirect(request.POST.get("next") or "alerts:list")


@require_permission(roles.VIEW_OPERATIONS)
def banner(request: HttpRequest) -> JsonResponse:
    """Polled by the banner script in base.html every few seconds."""
    return JsonResponse(selectors.banner())
