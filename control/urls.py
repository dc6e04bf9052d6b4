"""URLs of the live page."""

from django.urls import path

from control import views

app_name = "control"
urlpatterns = [
    path("", views.live_page, name="live"),
    path("live/vehicles.json", views.vehicles_json, name="vehicles-json"),
    path("live/orders.json", views.orders_json, name="orders-json"),
    path("health", views.health, name="health"),
]
