"""URLs of the live page."""

from django.urls import path

from control import operations_views, vehicle_views, views

app_name = "control"
urlpatterns = [
    path("", views.live_page, name="live"),
    path("live/vehicles.json", views.vehicles_json, name="vehicles-json"),
    path("live/orders.json", views.orders_json, name="orders-json"),
    path("health", views.health, name="health"),
    path("ready", views.ready, name="ready"),
    path("overview/", operations_views.overview_page, name="overview"),
    path("vehicles/", operations_views.vehicles_page, name="vehicles"),
    path(
        "vehicles/<str:manufacturer>/<str:serial>/",
        vehicle_views.vehicle_page,
        name="vehicle-detail",
    ),
    path(
        "vehicles/<str:manufacturer>/<str:serial>/command/",
        vehicle_views.vehicle_command,
        name="vehicle-command",
    ),
]
