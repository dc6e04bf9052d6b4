"""Websocket routes."""

from django.urls import path

from control.consumers import LiveConsumer
from control.vehicle_consumers import VehicleConsumer

websocket_urlpatterns = [
    path("ws/live/", LiveConsumer.as_asgi()),
    path("ws/vehicles/<int:pk>/", VehicleConsumer.as_asgi()),
]
