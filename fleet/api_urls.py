"""REST API v1 for integrations, collected from the apps, with its OpenAPI schema and docs."""

from django.urls import include, path, register_converter
from drf_spectacular.views import SpectacularAPIView, SpectacularRedocView, SpectacularSwaggerView


class IdConverter:
    """A database id in a path: 1 to 18 digits, so a larger number is a 404, not an overflow."""

    regex = "[0-9]{1,18}"

    def to_python(self, value: str) -> int:
        return int(value)

    def to_url(self, value: int) -> str:
        return str(value)


register_converter(IdConverter, "id")


class LocalRedocView(SpectacularRedocView):
    """Redoc from the sidecar package, on a page that loads no web fonts from outside."""

    template_name = "orders/redoc.html"


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
