"""URLs of the alert pages."""

from django.urls import path, re_path

from alerts import views

app_name = "alerts"

urlpatterns = [
    path("", views.alert_list, name="list"),
    path("banner.json", views.banner, name="banner"),
    re_path(
        r"^(?P<pk>[0-9]{1,18})/(?P<action>acknowledge|resolve)/$", views.alert_action, name="action"
    ),
]
