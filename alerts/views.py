"""Pages of the alerts app: the list (acknowledge/resolve with a comment) and the banner feed."""

from django.contrib import messages
from django.contrib.auth.decorators import login_required
from django.http import HttpRequest, HttpResponse, JsonResponse
from django.shortcuts import redirect, render
from django.views.decorators.http import require_POST

from alerts import selectors, services
from alerts.models import Alert, Severity, Source
from fleet.exceptions import DomainError


@login_required
def alert_list(request: HttpRequest) -> HttpResponse:
    show = request.GET.get("show", "open")
    alerts = selectors.open_alerts() if show == "open" else Alert.objects.select_related("vehicle")
    source = request.GET.get("source", "")
    if source in Source.values:
        alerts = alerts.filter(source=source)
    severity = request.GET.get("severity", "")
    if severity in Severity.values:
        alerts = alerts.filter(severity=severity)
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
        },
    )


@login_required
@require_POST
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


@login_required
def banner(request: HttpRequest) -> JsonResponse:
    """Polled by the banner script in base.html every few seconds."""
    return JsonResponse(selectors.banner())
