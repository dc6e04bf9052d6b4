from django.urls import path

from orders.api import views

urlpatterns = [
    path("orders/", views.TransportOrderListCreateApi.as_view(), name="order-list"),
    path("orders/<int:pk>/", views.TransportOrderDetailApi.as_view(), name="order-detail"),
    path("orders/<int:pk>/cancel/", views.TransportOrderCancelApi.as_view(), name="order-cancel"),
]
