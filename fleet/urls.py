"""Top-level URL routing: admin, pages, API."""

from django.contrib import admin
from django.urls import include, path

urlpatterns = [
    path("admin/", admin.site.urls),
    path("api/v1/", include("fleet.api_urls")),
    path("layouts/", include("maps.urls")),
    path("", include("control.urls")),
]
