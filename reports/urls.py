"""Report pages: /reports/ and /reports/<name>.csv."""

from django.urls import path

from reports import views

app_name = "reports"
urlpatterns = [
    path("", views.report_page, name="page"),
    path("<slug:name>.csv", views.export_csv, name="csv"),
]
