"""REST API v1 for integrations, collected from the apps, with its OpenAPI schema and docs."""

from typing import Any

from django.urls import include, path, register_converter
from drf_spectacular.views import SpectacularAPIView, SpectacularRedocView, SpectacularSwaggerView
from rest_framework.request import Request
from rest_framework.response import Response


class IdConverter:
    """A database id in a path: 1 to 18 digits, so a larger number is a 404, not an overflow."""

    regex = "[0-9]{1,18}"

    def to_python(self, value: str) -> int:
        return int(value)

    def to_url(self, value: int) -> str:
        return str(value)


register_converter(IdConverter, "id")


class LocalRedocView(SpectacularRedocView):
    """Redoc from the sidecar package, on a page that loads nothing from outside: no web fonts
    (the template), and no footer logo, which the bundle fetches from cdn.redoc.ly. The page's
    policy allows images from the app only, and Redoc drops the logo when it fails to load."""

    template_name = "orders/redoc.html"

    def finalize_response(
        self, request: Request, response: Response, *args: Any, **kwargs: Any
    ) -> Response:
        response = super().finalize_response(request, response, *args, **kwargs)
        response["Content-Security-Policy"] = "img-src 'self' data:"
        return response


urlpatterns = [
    path("", include("orders.api.urls")),
    path("", include("orders.api.inventory_urls")),
    path("", include("robots.api.urls")),
    path("", include("maps.api.urls")),
    path("", include("battery.api.urls")),
    path("", include("maintenance.api.urls")),
    path("schema/", SpectacularAPIView.as_view(), name="api-schema"),
    path("docs/", SpectacularSwaggerView.as_view(url_name="api-schema"), name="api-docs"),
    path("redoc/", LocalRedocView.as_view(url_name="api-schema"), name="api-redoc"),
]
