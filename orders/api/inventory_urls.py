"""URLs of the inventory's ERP API (owned by the orders layer: a move creates an order)."""

from django.urls import path

from orders.api import inventory_views

urlpatterns = [
    path("loads/<str:load_id>/", inventory_views.LoadLocationApi.as_view(), name="load-location"),
    path("loads/<str:load_id>/move/", inventory_views.LoadMoveApi.as_view(), name="load-move"),
]
