"""The live page and the JSON it refreshes from."""

from typing import Any

from django.contrib.auth.decorators import login_required, permission_required
from django.http import HttpRequest, HttpResponse, JsonResponse
from django.shortcuts import render

from control import readiness, selectors
from fleet import roles


@login_required
@permission_required(roles.VIEW_OPERATIONS, raise_exception=True)
def live_page(request: HttpRequest) -> HttpResponse:
    """The fleet live: the layout on a canvas, vehicles moving on it, vehicle and order lists."""
    return render(
        request,
        "control/live.html",
        {
            "layout": selectors.get_live_layout(),
            "vehicles": selectors.list_vehicle_rows(),
            "orders": selectors.list_order_rows(),
        },
    )


@login_required
@permission_required(roles.VIEW_OPERATIONS, raise_exception=True)
def vehicles_json(request: HttpRequest) -> JsonResponse:
    return JsonResponse({"vehicles": selectors.list_vehicle_rows()})


@login_required
@permission_required(roles.VIEW_OPERATIONS, raise_exception=True)
def orders_json(request: HttpRequest) -> JsonResponse:
    return JsonResponse({"orders": selectors.list_order_rows()})


def health(request: HttpRequest) -> JsonResponse:
    """Liveness for load balancers and the demo smoke test (no login)."""
    payload: dict[str, Any] = {"status": "ok"}
    return JsonResponse(payload)


def ready(request: HttpRequest) -> JsonResponse:
    """Readiness (no login): database, Redis and a leading control process; 503 if not."""
    payload = readiness.web_readiness()
    return JsonResponse(payload, status=200 if payload["ready"] else 503)
