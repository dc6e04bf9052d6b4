"""Top-level URL routing: admin, pages, API."""

from django.contrib import admin
from django.urls import include, path

from fleet import media, views

handler500 = "fleet.middleware.server_error"  # database down: 503, not 500

urlpatterns = [
    path("admin/", admin.site.urls),
    path("accounts/", include("django.contrib.auth.urls")),  # login for staff who are not admins
    path("audit/", views.audit_page, name="audit"),
    path("audit.csv", views.audit_csv, name="audit-csv"),
    path("media/<path:name>", media.media_file, name="media"),
    path("api/v1/", include("fleet.api_urls")),
    path("layouts/", include("maps.urls")),
    path("reports/", include("reports.urls")),
    path("orders/", include("orders.urls")),
    path("energy/", include("battery.urls")),
    path("maintenance/", include("maintenance.urls")),
    path("alerts/", include("alerts.urls")),
    path("inventory/", include("inventory.urls")),
    path("metrics", include("control.metrics_urls")),  # Prometheus scrape (no login)
    path("", include("control.urls")),
]
