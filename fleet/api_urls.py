"""REST API v1 for integrations, collected from the apps."""

from django.urls import include, path

urlpatterns = [
    path("", include("orders.api.urls")),
    path("", include("robots.api.urls")),
    path("", include("maps.api.urls")),
]
